#!/bin/bash
# Checks that the C++ sources follow .clang-format (clang-format --dry-run --Werror): every
# tracked *.h and *.cpp, or the files named. GLSL (shaders/*.glsl, shaders/ray/*.glsl) is
# outside clang-format's languages and is kept by hand. Fix a failure with
#   git ls-files '*.h' '*.cpp' | xargs clang-format -i
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
cd "$root"
command -v clang-format >/dev/null || { echo "check_format: clang-format is not installed (apt-get install clang-format)" >&2; exit 2; }
if [ $# -gt 0 ]; then
  files=("$@")
elif git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -t files < <(git ls-files '*.h' '*.cpp' | grep -v node_modules)
else
  mapfile -t files < <(find server tests shaders client-python -name node_modules -prune -o \( -name '*.h' -o -name '*.cpp' \) -print)
fi
if ! clang-format --style="file:$root/.clang-format" --dry-run --Werror "${files[@]}"; then
  echo "check_format: fix with: git ls-files '*.h' '*.cpp' | xargs clang-format -i" >&2
  exit 1
fi
echo "check_format: ${#files[@]} files follow .clang-format"
