#!/usr/bin/env python3
"""The documentation matches the program: every relative link in README.md, docs/, proto/ and
the folders' READMEs resolves to a file (and a heading, for #anchors), and every sub-command and
flag the docs name for `peakcast` or `peakcast-bench` is one their --help lists. The commands of
the docs' scripts (scripts/*.py) are checked against their own --help."""
import os, pathlib, re, subprocess, sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
PEAKCAST = os.environ.get("PEAKCAST_BIN", str(ROOT / "build/server/peakcast"))
BENCH = os.environ.get("PEAKCAST_BENCH_BIN", str(ROOT / "build/server/peakcast-bench"))
SCRIPTS = {"bench_peers.py": ROOT / "scripts/bench_peers.py", "bench_memory.py": ROOT / "scripts/bench_memory.py",
           "bench_ab.py": ROOT / "scripts/bench_ab.py"}


def docs():
    files = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md")), ROOT / "proto/messages.md"]
    files += [p for p in ROOT.glob("*/**/README.md")
              if not any(part.startswith((".", "build")) or part in ("node_modules", "__pycache__")
                         for part in p.relative_to(ROOT).parts)]
    return [f for f in files if f.exists()]


def help_text(cmd):
    r = subprocess.run(cmd + ["--help"], capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, (cmd, r.stderr)
    return r.stdout


def subcommands(binary):
    text = help_text([binary])
    block = text.split("Subcommands:", 1)[1] if "Subcommands:" in text else ""
    return set(re.findall(r"^\s{2}([a-z][a-z0-9-]*)\s", block, re.M))


def flags(text):
    return set(re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*)", text))


def anchors(md):
    """GitHub's heading anchors: lower case, punctuation dropped, spaces to '-'."""
    out = set()
    for h in re.findall(r"^#+\s+(.*)$", md.read_text(), re.M):
        a = re.sub(r"[^\w\- ]", "", h.strip().lower().replace("`", "")).replace(" ", "-")
        out.add(a)
    return out


def test_every_relative_link_resolves():
    bad = []
    for f in docs():
        text = f.read_text()
        # Links outside code: [text](target) and <img src>, skipping fenced blocks.
        text = re.sub(r"```.*?```", "", text, flags=re.S)
        for target in re.findall(r"\]\(([^)\s]+)\)", text):
            if re.match(r"^[a-z]+:", target) or target.startswith("#") and not target[1:]:
                continue
            path, _, anchor = target.partition("#")
            dest = (f.parent / path).resolve() if path else f
            if not dest.exists():
                bad.append(f"{f.relative_to(ROOT)}: {target} (no such file)")
            elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
                bad.append(f"{f.relative_to(ROOT)}: {target} (no heading #{anchor})")
    assert not bad, "broken links:\n" + "\n".join(bad)


def commands_in(text):
    """(binary, words) for every command line of peakcast or peakcast-bench the text shows: in
    code blocks (continued lines joined) and in inline code."""
    found = []
    for block in re.findall(r"```[a-z]*\n(.*?)```", text, re.S):
        block = re.sub(r"\\\n\s*", " ", block)
        for line in block.splitlines():
            found += commands_on(line)
    for span in re.findall(r"`([^`\n]+)`", re.sub(r"```.*?```", "", text, flags=re.S)):
        found += commands_on(span)
    return found


def commands_on(line):
    line = line.split("#", 1)[0] if not line.lstrip().startswith("#") else ""
    out = []
    for m in re.finditer(r"(?:^|[\s/;(|&])(peakcast-bench|peakcast)\s+([a-z][a-z0-9-]*)((?:\s+[^|;&]*)?)", line):
        out.append((m.group(1), m.group(2), m.group(3)))
    return out


def test_every_named_subcommand_and_flag_exists():
    binaries = {"peakcast": PEAKCAST, "peakcast-bench": BENCH}
    subs = {name: subcommands(path) for name, path in binaries.items()}
    helps = {}
    bad = []
    mentioned = set()
    for f in docs():
        text = f.read_text()
        for name, sub, rest in commands_in(text):
            if sub not in subs[name]:
                # Prose such as "peakcast serves ..." in inline code is rare; a word that is not a
                # sub-command of either binary is reported.
                bad.append(f"{f.relative_to(ROOT)}: `{name} {sub}`: no such sub-command")
                continue
            key = (name, sub)
            if key not in helps:
                helps[key] = flags(help_text([binaries[name], sub]))
            for flag in flags(rest):
                mentioned.add(flag)
                if flag not in helps[key]:
                    bad.append(f"{f.relative_to(ROOT)}: `{name} {sub} {flag}`: not in `{name} {sub} --help`")
    # Flags named on their own (`--backend`) must belong to some command the docs describe.
    every = set().union(*helps.values()) if helps else set()
    for name, path in binaries.items():
        every |= flags(help_text([path]))
        for sub in subs[name]:
            every |= flags(help_text([path, sub]))
    for script in SCRIPTS.values():
        every |= flags(help_text([sys.executable, str(script)]))
    other_tools = {"--oversubscribe", "--output-on-failure", "--no-install-recommends", "--rm", "--gpus", "--headless",
                   "--no-sandbox", "--network", "--name", "--env-file", "--mpi", "--test-dir", "--target", "--build",
                   "--from", "--cap-add", "--privileged", "--volume", "--user-data-dir", "--disable-gpu", "--timeout",
                   "--ntasks", "--ntasks-per-node", "--nodes", "--gres", "--host", "--bind-to", "--map-by", "--mca", "--cpus-per-task",
                   "--read-only", "--tmpfs", "--security-opt", "--publish", "--detach", "--file", "--isolation",
                   "--layers", "--tag", "--storage-driver", "--version", "--help", "--preset"}
    for f in docs():
        text = re.sub(r"```.*?```", "", f.read_text(), flags=re.S)
        for span in re.findall(r"`([^`\n]+)`", text):
            if re.match(r"^\s*(mpirun|docker|kubectl|buildah|ctest|cmake|apt|apt-get|srun|node|npm|python3|podman|curl)\b",
                        span):
                continue
            if span.strip().startswith("--"):
                for flag in flags(span.split()[0]):
                    if flag not in every and flag not in other_tools:
                        bad.append(f"{f.relative_to(ROOT)}: `{flag}`: no command of peakcast, peakcast-bench or "
                                   f"scripts/ has it")
    assert not bad, "the docs name what the programs do not have:\n" + "\n".join(sorted(set(bad)))


def test_the_checks_above_can_fail():
    """The extraction finds commands and flags (a parser that finds nothing would pass anything)."""
    sample = "```sh\npeakcast render s.json -o x.png --stats st.json\npeakcast-bench scene s.json \\\n  --frames 3\n```\n" \
             "and `peakcast serve --port 9`"
    cmds = commands_in(sample)
    assert ("peakcast", "render", " s.json -o x.png --stats st.json") in cmds, cmds
    assert any(c[:2] == ("peakcast-bench", "scene") and "--frames" in c[2] for c in cmds), cmds
    assert any(c[:2] == ("peakcast", "serve") and "--port" in c[2] for c in cmds), cmds
    assert "--stats" in flags(help_text([PEAKCAST, "render"]))
    assert "--nonsense" not in flags(help_text([PEAKCAST, "render"]))


if __name__ == "__main__":
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
    import script_tests

    script_tests.run(globals())
