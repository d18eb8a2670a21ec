#!/usr/bin/env python3
"""No function over 80 lines in server/ and shaders/ (docs/architecture.md, "Function length").

Counts each top-level function from the line of its opening brace to its closing brace (the
lambdas inside it included; member functions defined inside a class body are not counted).
The exceptions are the ones docs/architecture.md names in its "Function length" list, as
`path:function`; a listed function that is no longer long is reported too, so the list stays
true. Exit status 1 on any finding. With files as arguments, checks only those (no exceptions).
"""
import pathlib
import re
import subprocess
import sys

LIMIT = 80
ROOT = pathlib.Path(__file__).resolve().parent.parent


def long_functions(path, text):
    lines = text.split("\n")
    depth, start, name, found = 0, None, None, []
    for i, line in enumerate(lines):
        code = re.sub(r"//.*", "", line)
        code = re.sub(r'"(\\.|[^"\\])*"', '""', code)
        if depth == 0 and "{" in code:
            sig = " ".join(lines[max(0, i - 2) : i + 1])
            m = re.findall(r"([A-Za-z_][\w:<>~]*)\s*\([^;{}]*\)\s*(const)?\s*(noexcept)?\s*(override)?\s*(->[^{]*)?\{", sig)
            kind = re.match(r"\s*(namespace|struct|class|enum|union|extern)\b", code)
            if m and not kind and not re.search(r"\b(namespace|class|struct)\b[^(]*\{", code):
                start, name = i, m[-1][0]
            else:
                start = None
        for ch in code:
            if ch == "{":
                depth += 1
            elif ch == "}":
                depth -= 1
                if depth == 0 and start is not None:
                    if i - start + 1 > LIMIT:
                        found.append((i - start + 1, f"{path}:{name}", start + 1))
                    start = None
        if re.match(r"\s*namespace\b.*\{\s*$", code) or re.match(r'\s*(extern "C"|HWY_BEFORE_NAMESPACE).*\{', code):
            depth -= code.count("{")
        if re.match(r"^\}\s*//\s*namespace", line):
            depth += 1
    return found


def exceptions():
    doc = (ROOT / "docs/architecture.md").read_text()
    m = re.search(r"^### Function length\n(.*?)(?=^#)", doc, re.S | re.M)
    return set(re.findall(r"^- `([^`]+:[^`]+)`", m.group(1), re.M)) if m else set()


def main(argv):
    if argv:
        files, allowed = argv, set()
    else:
        listed = subprocess.check_output(["git", "ls-files", "server", "shaders"], cwd=ROOT, text=True).split()
        files, allowed = [f for f in listed if f.endswith((".cpp", ".h", ".glsl", ".frag", ".comp"))], exceptions()
    bad, seen = [], set()
    for f in files:
        p = pathlib.Path(f) if argv else ROOT / f
        for n, key, line in long_functions(f, p.read_text(errors="replace")):
            seen.add(key)
            if key not in allowed:
                bad.append(f"{f}:{line}: {key.split(':')[-1]} is {n} lines (limit {LIMIT})")
    stale = sorted(allowed - seen)
    for key in stale:
        bad.append(f"docs/architecture.md names {key} as a long function, but it is not over {LIMIT} lines")
    for b in bad:
        print("check_function_length:", b)
    if not bad:
        print(f"check_function_length: {len(files)} files, no function over {LIMIT} lines but the named exceptions")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
