#!/usr/bin/env python3
"""Every serve option as flag, PEAKCAST_* variable and config-file key, one precedence
(flag > environment > file > default), --print-config, and each refusal named by its source."""
import os, pathlib, re, subprocess, sys, tempfile

PEAKCAST = os.environ["PEAKCAST_BIN"]
NOT_SETTINGS = {"help", "config", "print-config"}


def serve(args=(), env=None, check=True):
    clean = {k: v for k, v in os.environ.items() if not k.startswith("PEAKCAST_")}
    clean.update(env or {})
    r = subprocess.run([PEAKCAST, "serve", *args], env=clean, capture_output=True, text=True, timeout=60)
    if check:
        assert r.returncode == 0, (args, env, r.stdout, r.stderr)
    return r


def parse(printed):
    """key -> (value text, source) from --print-config."""
    out = {}
    for line in printed.splitlines():
        m = re.match(r"^(#\s*)?([a-z-]+) = (.*?)\s+# (.*)$", line)
        if m:
            out[m.group(2)] = (m.group(3), m.group(4))
    return out


def option_keys():
    """Every long option `serve --help` lists."""
    keys = re.findall(r"^\s+--([a-z][a-z-]*)", serve(["--help"]).stdout, re.M)
    return [k for k in dict.fromkeys(keys) if k not in NOT_SETTINGS]


def is_number(text):
    try:
        float(text)
        return True
    except ValueError:
        return False


def env_name(key):
    return "PEAKCAST_" + key.upper().replace("-", "_")


def test_defaults_listed_for_every_option():
    keys = option_keys()
    printed = parse(serve(["--print-config"]).stdout)
    assert len(keys) >= 19, keys
    assert set(printed) == set(keys), (set(keys) ^ set(printed))
    assert all(src == "default" for _, src in printed.values()), printed


# A value other than the default for every option: a new option without one fails the test below.
NON_DEFAULT = {"bind": "0.0.0.0", "port": "9123", "max-sessions": "5", "idle-timeout": "30", "max-fps": "24",
               "gpu-budget-mib": "512", "memory-budget-mib": "2048", "preview-voxels": "1000",
               "max-queued-stills": "2", "max-still-samples": "1e+09",
               "still-band-samples": "2e+07", "log-level": "debug", "log-format": "json", "io-threads": "3",
               "encode-threads": "3", "web-dir": "/tmp", "shader-dir": "/tmp", "egl-device": "surfaceless",
               "program-cache": "off", "upload-dir": "/tmp/peakcast-config-test-uploads", "max-upload-mib": "64",
               "upload-budget-mib": "128", "max-uploads": "3", "upload-timeout": "5",
               "uploads-per-minute": "10", "max-kbps": "2500",
               "backend": "cpu", "token-file": "/tmp/peakcast-config-test-token",
               "user-token-file": "/tmp/peakcast-config-test-users", "upload-min-rate-kib": "32",
               "upload-deadline": "60"}


def test_every_option_by_flag_env_and_file():
    """Each option set the three ways to a value that is not its default: printed with that value
    and that source."""
    defaults = parse(serve(["--print-config"]).stdout)
    with tempfile.TemporaryDirectory() as tmp:
        for key, (default, _) in defaults.items():
            if key == "token":
                raw, printed = "s3cret", None
            elif default.startswith("["):
                raw, printed = tmp, f'["{tmp}"]'
            else:
                assert key in NON_DEFAULT, f"give --{key} a non-default value in NON_DEFAULT"
                raw = NON_DEFAULT[key]
                printed = raw if is_number(raw) else f'"{raw}"'
                assert printed != default, (key, default)
            toml = f'"{raw}"' if printed is None or printed.startswith('"') else (f'["{raw}"]' if printed.startswith("[") else raw)
            cfg = pathlib.Path(tmp, f"{key}.toml")
            cfg.write_text(f"{key} = {toml}\n")
            for args, env, source in (([f"--{key}", raw], {}, "flag"), ([], {env_name(key): raw}, f"env {env_name(key)}"),
                                      (["--config", str(cfg)], {}, f"file {cfg}")):
                value, src = parse(serve([*args, "--print-config"], env).stdout)[key]
                assert src == source, (key, source, src)
                if printed is None:
                    assert value == "(set, not printed)", (key, value)
                else:
                    assert value == printed, (key, source, value, printed)


def test_precedence_flag_env_file_default():
    with tempfile.TemporaryDirectory() as tmp:
        cfg = pathlib.Path(tmp, "serve.toml")
        cfg.write_text('port = 9001\nmax-fps = 21\nidle-timeout = 77\n[serve]\nlog-level = "debug"\n'
                       f'data = ["{tmp}", "/var"]\n')
        env = {"PEAKCAST_PORT": "9002", "PEAKCAST_MAX_FPS": "22", "PEAKCAST_CONFIG": str(cfg)}
        got = parse(serve(["--port", "9003", "--print-config"], env).stdout)
        assert got["port"] == ("9003", "flag"), got["port"]                       # flag over env and file
        assert got["max-fps"] == ("22", "env PEAKCAST_MAX_FPS"), got["max-fps"]  # env over file
        assert got["idle-timeout"] == ("77", f"file {cfg}"), got["idle-timeout"]  # file over default
        assert got["log-level"] == ('"debug"', f"file {cfg}"), got["log-level"]  # a [serve] section works
        assert got["data"] == (f'["{tmp}", "/var"]', f"file {cfg}"), got["data"]
        assert got["bind"] == ('"127.0.0.1"', "default"), got["bind"]
        # Lists: comma-separated in the environment, the flag repeated.
        got = parse(serve(["--print-config"], {"PEAKCAST_DATA": "/a,/b"}).stdout)
        assert got["data"][0] == '["/a", "/b"]', got["data"]
        got = parse(serve(["--data", "/c", "--data", "/d", "--print-config"], {"PEAKCAST_DATA": "/a"}).stdout)
        assert got["data"] == ('["/c", "/d"]', "flag"), got["data"]


def test_printed_config_reads_back_the_same():
    with tempfile.TemporaryDirectory() as tmp:
        first = serve(["--print-config", "--port", "9010", "--max-fps", "12.5", "--data", tmp,
                       "--log-format", "json"], {"PEAKCAST_BIND": "0.0.0.0"}).stdout
        cfg = pathlib.Path(tmp, "printed.toml")
        cfg.write_text(first)
        again = parse(serve(["--config", str(cfg), "--print-config"]).stdout)
        assert {k: v for k, (v, _) in again.items()} == {k: v for k, (v, _) in parse(first).items()}


def test_token_never_printed():
    out = serve(["--print-config"], {"PEAKCAST_TOKEN": "topsecret-123"}).stdout
    assert "topsecret-123" not in out and "# token = (set, not printed)" in out, out


def test_refusals_name_their_source():
    cases = [
        ({"PEAKCAST_PORT": "eighty"}, [], "PEAKCAST_PORT"),
        ({"PEAKCAST_MAX_FPS": "1000"}, [], "PEAKCAST_MAX_FPS"),
        ({"PEAKCAST_LOG_FORMAT": "xml"}, [], "PEAKCAST_LOG_FORMAT"),
        ({"PEAKCAST_EGL_DEVICE": "gpu0"}, [], "auto, surfaceless or a device index"),
        ({"PEAKCAST_BACKEND": "vulkan"}, [], "PEAKCAST_BACKEND"),
        ({}, ["--max-sessions", "0"], "--max-sessions"),
        ({"PEAKCAST_CONFIG": "/nonexistent/serve.toml"}, [], "/nonexistent/serve.toml"),
    ]
    with tempfile.TemporaryDirectory() as tmp:
        typo = pathlib.Path(tmp, "typo.toml")
        typo.write_text("prot = 8080\n")
        bad = pathlib.Path(tmp, "bad.toml")
        bad.write_text("io-threads = 99\n")
        cases += [({}, ["--config", str(typo)], "'prot' is not a serve option"),
                  ({}, ["--config", str(bad)], "key io-threads")]
        for env, args, expect in cases:
            r = serve([*args, "--print-config"], env, check=False)
            assert r.returncode == 2, (env, args, r.returncode, r.stdout, r.stderr)
            assert expect in r.stderr, (env, args, r.stderr)
            assert "# Precedence" not in r.stdout, "nothing printed for a refused configuration"


def test_token_and_host_options_refused_by_name():
    """The access options: a token file that cannot be read or holds no token, user tokens that are
    not "NAME TOKEN", a token given twice, an allowed host that is not a host name: exit 2 naming
    the option, never serving with less protection than asked for (and never printing a token)."""
    with tempfile.TemporaryDirectory() as tmp:
        empty = pathlib.Path(tmp, "empty")
        empty.write_text("\n")
        users = pathlib.Path(tmp, "users")
        users.write_text("alice tok-a\nbob\n")
        twice = pathlib.Path(tmp, "twice")
        twice.write_text("alice tok-a\nalice tok-b\n")
        token = pathlib.Path(tmp, "token")
        token.write_text("s3cret-from-file\n")
        cases = [(["--token-file", "/nonexistent/token"], "--token-file"),
                 (["--token-file", str(empty)], "holds no token"),
                 (["--user-token-file", str(users)], "line 2"),
                 (["--user-token-file", str(twice)], "used twice"),
                 (["--token", "a", "--token-file", str(token)], "not both"),
                 (["--allowed-host", "*.example.org"], "--allowed-host"),
                 (["--allowed-host", "evil.example/x"], "--allowed-host")]
        for args, expect in cases:
            r = serve([*args, "--port", "0", "--io-threads", "1"], check=False)
            assert r.returncode != 0, (args, r.stdout)
            assert expect in r.stderr, (args, r.stderr)
            assert "tok-a" not in r.stderr and "s3cret" not in r.stderr, (args, r.stderr)


def test_layered_values_reach_the_server():
    """Not only the printout: a server started from a file, the environment and a flag runs with
    them (its health reports max-sessions and queued stills; the GL line names the EGL device)."""
    import json, signal, urllib.request
    with tempfile.TemporaryDirectory() as tmp:
        cfg = pathlib.Path(tmp, "serve.toml")
        # egl-device only in the file: the EGL context's own PEAKCAST_EGL_DEVICE is unset, so only
        # the configuration can choose surfaceless (auto would take device 0).
        # backend = "gl" from the file too: auto would choose the CPU backend on llvmpipe and open
        # no GL context to name.
        cfg.write_text('max-sessions = 5\nmax-queued-stills = 3\nidle-timeout = 42\negl-device = "surfaceless"\n'
                       'backend = "gl"\n')
        env = {k: v for k, v in os.environ.items() if not k.startswith("PEAKCAST_")}
        env.update({"PEAKCAST_CONFIG": str(cfg), "PEAKCAST_MAX_QUEUED_STILLS": "7"})
        p = subprocess.Popen([PEAKCAST, "serve", "--port", "0", "--max-sessions", "6"], env=env,
                             stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
        try:
            line = p.stdout.readline()
            assert "EGL surfaceless" in line, line
            port = re.search(r":(\d+) \(renderer gl: ", line).group(1)
            health = json.load(urllib.request.urlopen(f"http://127.0.0.1:{port}/api/health", timeout=30))
            assert health["max_sessions"] == 6 and health["max_queued_stills"] == 7, health  # flag, env
            assert health["backend"] == "gl", health  # file
        finally:
            p.send_signal(signal.SIGTERM)
            p.wait(timeout=10)


if __name__ == "__main__":
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
    import script_tests

    script_tests.run(globals())
