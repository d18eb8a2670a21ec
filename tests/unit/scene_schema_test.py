#!/usr/bin/env python3
"""proto/scene.schema.json accepts tests/data/scenes/good and refuses tests/data/scenes/bad; the C++
parser is run on the same files by `peakcast reference` (good: renders; bad: exit 2 naming the key).
bad_semantic/ holds rules JSON Schema cannot say (sorted TF, up not parallel to the view): the
schema accepts them, the C++ parser must refuse them."""
import json, pathlib, subprocess, sys, tempfile

import jsonschema

root = pathlib.Path(__file__).resolve().parents[2]
peakcast = sys.argv[1]
schema = json.loads((root / "proto/scene.schema.json").read_text())
jsonschema.Draft202012Validator.check_schema(schema)
validator = jsonschema.Draft202012Validator(schema)
scenes = root / "tests/data/scenes"
failures = 0
with tempfile.TemporaryDirectory() as tmp:
    for kind in ("good", "bad", "bad_semantic"):
        for path in sorted((scenes / kind).glob("*.json")):
            scene = json.loads(path.read_text())
            errors = list(validator.iter_errors(scene))
            scene["volume"] = str(root / "tests/data" / scene["volume"])
            staged = pathlib.Path(tmp) / path.name
            staged.write_text(json.dumps(scene))
            run = subprocess.run([peakcast, "reference", str(staged), "-o", str(pathlib.Path(tmp) / "out.png")],
                                 capture_output=True, text=True)
            schema_ok, cpp_ok = not errors, run.returncode == 0
            expect_schema, expect_cpp = {"good": (True, True), "bad": (False, False), "bad_semantic": (True, False)}[kind]
            status = "ok" if (schema_ok == expect_schema and cpp_ok == expect_cpp) else "FAIL"
            failures += status == "FAIL"
            reason = errors[0].message if errors else ""
            print(f"{status} {kind}/{path.name}: schema {'accepts' if schema_ok else 'refuses'} ({reason[:60]}); "
                  f"C++ exit {run.returncode} {run.stderr.strip()[:100]}")
            if not cpp_ok and run.returncode != 2:
                print(f"FAIL {path.name}: C++ refusal must exit 2"); failures += 1
total = sum(1 for k in ("good", "bad", "bad_semantic") for _ in (scenes / k).glob("*.json"))
print(f"{total - failures} passed, {failures} failed")
sys.exit(1 if failures else 0)
