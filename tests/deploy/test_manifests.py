#!/usr/bin/env python3
"""docker/compose.yaml and docker/k8s/ parse, and hang together: ports, probes on
/api/health, the token from a secret or env file, the data volume, one GPU, sticky routing."""
import os, pathlib, re, shutil, subprocess, sys

import yaml

DOCKER = pathlib.Path(__file__).resolve().parents[2] / "docker"


def load_all(path):
    return [d for d in yaml.safe_load_all(path.read_text()) if d]


def dockerfile():
    text = (DOCKER / "Dockerfile").read_text()
    env = dict(re.findall(r"(PEAKCAST_[A-Z_]+)=(\S+)", text))
    return text, env


def test_compose():
    doc = load_all(DOCKER / "compose.yaml")[0]
    svc = doc["services"]["peakcast"]
    assert (DOCKER / svc["build"]["context"] / svc["build"]["dockerfile"]).is_file()
    assert svc["env_file"] == ["peakcast.env"] and (DOCKER / "peakcast.env.example").is_file()
    assert "PEAKCAST_TOKEN=" in (DOCKER / "peakcast.env.example").read_text()
    assert any(re.search(r":/data(:ro)?$", v) for v in svc["volumes"]), svc["volumes"]
    # Uploads: the image's upload folder, a volume of its own, outside the read-only data.
    _, env = dockerfile()
    assert any(v.endswith(":" + env["PEAKCAST_UPLOAD_DIR"]) for v in svc["volumes"]), svc["volumes"]
    assert not env["PEAKCAST_UPLOAD_DIR"].startswith("/data")
    _, env = dockerfile()
    host, container = svc["ports"][0].rsplit(":", 1)
    assert container == env["PEAKCAST_PORT"] and host.startswith("127.0.0.1:"), svc["ports"]
    assert svc["healthcheck"]["test"] == ["CMD", "peakcast-healthcheck"]
    gpu = load_all(DOCKER / "compose.gpu.yaml")[0]["services"]["peakcast"]
    assert "graphics" in gpu["environment"]["NVIDIA_DRIVER_CAPABILITIES"]
    dev = gpu["deploy"]["resources"]["reservations"]["devices"][0]
    assert dev["driver"] == "nvidia" and dev["count"] == 1
    # The compose CLI's own parse, where it is installed (it needs no engine).
    if shutil.which("docker") and subprocess.run(["docker", "compose", "version"], capture_output=True).returncode == 0:
        env_file = DOCKER / "peakcast.env"
        made = not env_file.exists()
        if made:
            shutil.copy(DOCKER / "peakcast.env.example", env_file)
        try:
            subprocess.run(["docker", "compose", "-f", DOCKER / "compose.yaml", "config", "-q"], check=True)
        finally:
            if made:
                env_file.unlink()


def test_kubernetes():
    docs = {}
    for f in sorted((DOCKER / "k8s").glob("*.yaml")):
        for d in load_all(f):
            assert "kind" in d and "apiVersion" in d, f
            docs.setdefault(d["kind"], []).append(d)
    kustom = docs.pop("Kustomization")[0]
    for r in kustom["resources"]:
        assert (DOCKER / "k8s" / r).is_file(), r
    assert {"Deployment", "Service", "Ingress", "PersistentVolume", "PersistentVolumeClaim", "Secret"} <= set(docs)
    dep, svc, ing = docs["Deployment"][0], docs["Service"][0], docs["Ingress"][0]
    pod = dep["spec"]["template"]["spec"]
    c = pod["containers"][0]
    port = c["ports"][0]
    _, env = dockerfile()
    assert str(port["containerPort"]) == env["PEAKCAST_PORT"]
    for probe in ("readinessProbe", "livenessProbe"):
        get = c[probe]["httpGet"]
        assert get["path"] == "/api/health" and get["port"] == port["name"], (probe, get)
    assert c["resources"]["limits"]["nvidia.com/gpu"] == 1
    assert {"cpu", "memory"} <= set(c["resources"]["limits"]) and {"cpu", "memory"} <= set(c["resources"]["requests"])
    env_vars = {e["name"]: e for e in c["env"]}
    secret = env_vars["PEAKCAST_TOKEN"]["valueFrom"]["secretKeyRef"]
    assert secret["name"] == docs["Secret"][0]["metadata"]["name"] and secret["key"] in docs["Secret"][0]["stringData"]
    assert "graphics" in env_vars["NVIDIA_DRIVER_CAPABILITIES"]["value"]
    assert pod["securityContext"]["runAsNonRoot"] and pod["securityContext"]["runAsUser"] != 0
    assert "USER peakcast" in dockerfile()[0] and "--uid 10001" in dockerfile()[0]
    assert pod["securityContext"]["runAsUser"] == 10001
    assert any(m["mountPath"] == env["PEAKCAST_UPLOAD_DIR"] and not m.get("readOnly") for m in c["volumeMounts"])
    # The data volume: a claim bound to the PersistentVolume, mounted at /data.
    mount = next(m for m in c["volumeMounts"] if m["mountPath"] == "/data")
    vol = next(v for v in pod["volumes"] if v["name"] == mount["name"])
    claim = docs["PersistentVolumeClaim"][0]
    assert vol["persistentVolumeClaim"]["claimName"] == claim["metadata"]["name"]
    assert claim["spec"]["storageClassName"] == docs["PersistentVolume"][0]["spec"]["storageClassName"]
    # Service selects the pods, Ingress routes to the Service, sticky for WebSocket sessions.
    labels = dep["spec"]["template"]["metadata"]["labels"]
    assert all(labels.get(k) == v for k, v in svc["spec"]["selector"].items())
    assert svc["spec"]["ports"][0]["targetPort"] == port["name"]
    backend = ing["spec"]["rules"][0]["http"]["paths"][0]["backend"]["service"]
    assert backend["name"] == svc["metadata"]["name"] and backend["port"]["name"] == svc["spec"]["ports"][0]["name"]
    ann = ing["metadata"]["annotations"]
    assert ann["nginx.ingress.kubernetes.io/affinity"] == "cookie"
    assert int(ann["nginx.ingress.kubernetes.io/proxy-read-timeout"]) >= 600


if __name__ == "__main__":
    failed = 0
    tests = [v for k, v in list(globals().items()) if k.startswith("test_")]
    for t in tests:
        try:
            t()
            print(f"ok   {t.__name__}")
        except Exception:
            import traceback
            traceback.print_exc()
            print(f"FAIL {t.__name__}")
            failed += 1
    print(f"{len(tests) - failed} passed, {failed} failed")
    sys.exit(1 if failed else 0)
