#!/usr/bin/env bash
# The format and lint checks (.clang-format, .clang-tidy at the top of the tree).
#   scripts/lint.sh              clang-format on every C++ file (a file that differs fails, with the diff),
#                                and clang-tidy on the sources changed since the last whole-tree lint
#                                (the commit in .ci/lint-base) and on one source of each header changed
#   scripts/lint.sh --all        clang-tidy on every source of the library and the program (about 25 min
#                                of CPU: run it, fix what it finds, then write `git rev-parse HEAD` into
#                                .ci/lint-base, so CI lints only what changed after)
#   scripts/lint.sh --format     rewrite every C++ file in clang-format's form
# clang-tidy reads the compile commands of a configure-only directory (build-lint, not a build: only
# the generated EGM protobuf headers are made), so it needs no build of its own.
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:-changed}
mapfile -t cxx < <(git ls-files '*.cpp' '*.hpp')

if [ "$mode" = "--format" ]; then
  clang-format -i "${cxx[@]}"
  exit 0
fi

echo "clang-format: ${#cxx[@]} files"
mapfile -t bad < <(clang-format --dry-run "${cxx[@]}" 2>&1 | sed -n 's/^\([^:]*\):[0-9]*:[0-9]*: \(warning\|error\): code should be clang-formatted.*/\1/p' | sort -u)
if [ ${#bad[@]} -gt 0 ]; then
  for f in "${bad[@]:0:5}"; do diff -u "$f" <(clang-format "$f") | head -40 || true; done
  echo "clang-format: ${#bad[@]} files differ from .clang-format's form (scripts/lint.sh --format rewrites them):"
  printf '  %s\n' "${bad[@]}"
  exit 1
fi

# The functions allowed over clang-tidy's 80 lines: each marked in the code and listed in
# docs/architecture.md ("Functions over 80 lines"); per file, as many marks as entries.
mark='NOLINTNEXTLINE(readability-function-size)'
list=$(sed -n '/^## Functions over 80 lines/,/^## /p' docs/architecture.md)
mismatch=0
while IFS= read -r f; do
  [ -n "$f" ] || continue
  in_code=$(git grep -c "$mark" -- "$f" | sed 's/.*://' || true)
  in_code=${in_code:-0}
  in_list=$(grep -c "^- \`$f\`" <<<"$list" || true)
  if [ "$in_code" != "$in_list" ]; then
    echo "function size: $f has $in_code marked function(s) over 80 lines, docs/architecture.md lists $in_list"
    mismatch=1
  fi
done < <({ git grep -l "$mark" -- 'src/*.cpp' 'src/*.hpp' 'apps/*.cpp' 'python/src/*.cpp' || true
  grep -o '^- `[^`]*`' <<<"$list" | sed 's/^- `//; s/`$//'; } | sort -u)
[ "$mismatch" -eq 0 ] || exit 1

# The sources to lint: the library's, the program's and the Python module's bindings (tests and
# benchmarks are left to the compiler's warnings).
if [ "$mode" = "--all" ]; then
  mapfile -t sources < <(git ls-files 'src/*.cpp' 'apps/*.cpp' 'python/src/*.cpp')
else
  base=$(sed -n '1p' .ci/lint-base)
  if ! git cat-file -e "$base^{commit}" 2>/dev/null; then
    echo "scripts/lint.sh: .ci/lint-base names $base, which this clone does not have (a shallow clone?)" >&2
    exit 2
  fi
  sources=()
  while IFS= read -r f; do
    [ -f "$f" ] || continue  # deleted since
    # Changes to comments alone (whole comment lines, whitespace) change nothing clang-tidy sees, unless
    # they touch a NOLINT.
    if [ -z "$(git diff -w -I '^[[:space:]]*//' "$base" HEAD -- "$f")" ] &&
      ! git diff "$base" HEAD -- "$f" | grep -q '^[-+].*NOLINT'; then
      continue
    fi
    case "$f" in
      *.cpp) sources+=("$f") ;;
      *.hpp)
        # A header is linted through the source of the same name, else the first source that includes it.
        src="${f%.hpp}.cpp"
        if [ ! -f "$src" ]; then
          case "$f" in
            python/src/*) inc=${f#python/src/} ;;
            *) inc=${f#src/} ;;
          esac
          src=$(git grep -l "#include \"$inc\"" -- 'src/*.cpp' 'apps/*.cpp' 'python/src/*.cpp' | head -n 1 || true)
        fi
        [ -n "$src" ] && sources+=("$src")
        ;;
    esac
  done < <(git diff --name-only "$base" HEAD -- 'src/*.cpp' 'src/*.hpp' 'apps/*.cpp' 'apps/*.hpp' 'python/src/*.cpp' \
    'python/src/*.hpp')
  mapfile -t sources < <(printf '%s\n' "${sources[@]}" | sort -u | sed '/^$/d')
fi
echo "clang-tidy: ${#sources[@]} sources${mode:+ ($mode)}"
[ ${#sources[@]} -eq 0 ] && exit 0

dir=build-lint
cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=Release -DCMAKE_UNITY_BUILD=OFF -DCMAKE_EXPORT_COMPILE_COMMANDS=ON \
  -DDEFLEX_BUILD_TESTS=OFF -DDEFLEX_BUILD_BENCHMARKS=OFF -DDEFLEX_PYTHON=ON >/dev/null
cmake --build "$dir" --target deflex_egm_proto -j"$(nproc)" >/dev/null  # the generated headers
printf '%s\n' "${sources[@]}" | xargs -P "$(nproc)" -n 1 clang-tidy -p "$dir" --quiet 2>&1 |
  grep -v '^[0-9]* warnings\? generated\.$' | tee "$dir/clang-tidy.log" || true
if grep -q 'error:' "$dir/clang-tidy.log"; then
  echo "clang-tidy: $(grep -c 'error:' "$dir/clang-tidy.log") findings (above; .clang-tidy names the checks)"
  exit 1
fi
echo "clang-tidy: clean"
