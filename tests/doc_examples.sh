#!/usr/bin/env bash
# CTest "doc_examples": every C++ block (```cpp) of README.md and docs/*.md is a complete program.
# Each block is written to a file of its own, with a #line directive so that the compiler names the
# Markdown file and line, and all are compiled and linked (not run) against the build tree's
# multislit package, as a user's project would build them (tests/doc_examples/CMakeLists.txt).
#   doc_examples.sh <source dir> <package dir> <work dir> <generator> <C compiler> <C++ compiler>
#                   <build type> [BUILD_TYPE_FLAGS=<its C++ flags>] [SANITIZE_FLAGS=<flags>]
#                   [CLANG_FORMAT=<clang-format>]
# With clang-format, each block must also follow the repository's .clang-format.
set -euo pipefail
src=$1 package=$2 work=$3 generator=$4 cc=$5 cxx=$6 build_type=$7
build_type_flags='' sanitize_flags='' clang_format=''
for arg in "${@:8}"; do
  case $arg in
    BUILD_TYPE_FLAGS=*) build_type_flags=${arg#*=} ;;
    SANITIZE_FLAGS=*) sanitize_flags=${arg#*=} ;;
    CLANG_FORMAT=*) clang_format=${arg#*=} ;;
    *) echo "doc_examples.sh: unknown argument '$arg'" >&2 && exit 2 ;;
  esac
done

# extract <markdown file, relative to $src>: its C++ blocks as $work/examples/<name>_<line>.cpp,
# where <line> is the block's first line. A file is rewritten only when its text changed, so a
# second run builds only what changed.
extract() {
  local rel=$1 name
  name=$(tr -c 'A-Za-z0-9\n' '_' <<<"$rel")
  awk -v rel="$rel" -v name="$name" -v out="$work/examples" '
    function finish() {
      close(tmp)
      if (system("cmp -s \"" tmp "\" \"" file "\" || cp \"" tmp "\" \"" file "\"") != 0) exit 1
      system("rm -f \"" tmp "\"")
    }
    !inside && /^[ \t]*```[ \t]*(cpp|c\+\+|cxx)[ \t]*$/ {
      inside = 1
      indent = index($0, "`") - 1
      file = sprintf("%s/%s_%d.cpp", out, name, NR + 1)
      tmp = file ".new"
      printf "#line %d \"%s\"\n", NR + 1, rel > tmp
      print file
      next
    }
    inside && /^[ \t]*```[ \t]*$/ { inside = 0; finish(); next }
    inside { print substr($0, indent + 1) > tmp }
    END {
      if (inside) {
        printf "%s: the C++ block of line %d is not closed\n", rel, NR > "/dev/stderr"
        exit 1
      }
    }' "$src/$rel"
}

mkdir -p "$work/examples"
cd "$src"
listed=()
for md in README.md docs/*.md; do
  [[ -f $md ]] || continue
  extract "$md" >"$work/blocks.txt"
  mapfile -t files <"$work/blocks.txt"
  listed+=("${files[@]}")
done
if ((${#listed[@]} == 0)); then
  echo "no C++ blocks found in README.md and docs/*.md" >&2
  exit 1
fi
# Blocks that are gone (edited away, moved to another line) are removed with their programs.
for f in "$work"/examples/*.cpp; do
  [[ " ${listed[*]} " == *" $f "* ]] || rm -f "$f" "$work/build/$(basename "$f" .cpp)"
done
echo "${#listed[@]} C++ blocks:"
printf '  %s\n' "${listed[@]#"$work/examples/"}"

if [[ -n $clang_format && $clang_format != *NOTFOUND && -x $clang_format ]]; then
  unformatted=0
  for f in "${listed[@]}"; do
    # The block without its #line directive, formatted with the repository's .clang-format.
    if ! diff -u --label "$(sed -n '1s/^#line \([0-9]*\) "\(.*\)"$/\2:\1/p' "$f")" \
      --label "clang-format" <(tail -n +2 "$f") \
      <(tail -n +2 "$f" | "$clang_format" --assume-filename="$src/doc_example.cpp"); then
      unformatted=1
    fi
  done
  if ((unformatted)); then
    echo "C++ blocks not formatted: apply the changes above ($("$clang_format" --version))" >&2
    exit 1
  fi
fi

flags=(-DCMAKE_BUILD_TYPE="$build_type" -DCMAKE_C_COMPILER="$cc" -DCMAKE_CXX_COMPILER="$cxx")
# A static library built with sanitizers needs them in the program that links it too.
if [[ -n $sanitize_flags ]]; then
  flags+=("-DCMAKE_CXX_FLAGS=$sanitize_flags")
fi
if [[ -n $build_type && -n $build_type_flags ]]; then
  flags+=("-DCMAKE_CXX_FLAGS_${build_type^^}=$build_type_flags")
fi
cmake -S "$src/tests/doc_examples" -B "$work/build" -G "$generator" -Dmultislit_DIR="$package" \
  -DEXAMPLES_DIR="$work/examples" -DCMAKE_FIND_PACKAGE_NO_PACKAGE_REGISTRY=ON "${flags[@]}" \
  >"$work/configure.log" || {
  cat "$work/configure.log"
  exit 1
}
# Two compilers at once (DOC_EXAMPLES_JOBS): CTest counts this test as two processors (PROCESSORS
# in tests/CMakeLists.txt).
cmake --build "$work/build" --parallel "${DOC_EXAMPLES_JOBS:-2}"
echo "all ${#listed[@]} C++ blocks of README.md and docs/*.md compile and link"
