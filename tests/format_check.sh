#!/usr/bin/env bash
# CTest "format": our sources follow the repository's .clang-format.
#   format_check.sh <source dir> [clang-format]   exit 0 formatted, 1 not, 77 no clang-format
set -euo pipefail
src=$1
clang_format=${2:-}
if [[ -z $clang_format || $clang_format == *NOTFOUND || ! -x $clang_format ]]; then
  echo "clang-format not found: format check skipped"
  exit 77
fi
cd "$src"
mapfile -d '' files < <(find src include apps filters tests fuzz -type f \
  \( -name '*.cpp' -o -name '*.h' -o -name '*.hpp' \) -print0 2>/dev/null | sort -z)
if ((${#files[@]} == 0)); then
  echo "no sources found under $src" >&2
  exit 1
fi
if ! "$clang_format" --dry-run --Werror "${files[@]}"; then
  echo "not formatted: run clang-format -i on the files above ($("$clang_format" --version))" >&2
  exit 1
fi
echo "${#files[@]} files formatted ($("$clang_format" --version))"
