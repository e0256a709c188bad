#!/usr/bin/env bash
# test_citations — the repository's text follows its documentation rules (CONTRIBUTING.md):
#  1. no tracked *.md/*.c/*.h/*.py/*.sh file holds a pointer to the source material outside the
#     repository ("shared/reference") or to the removed scripts/diagnostics/, a temporary path (/tmp/..., except mktemp/TMPDIR lines,
#     "--out /tmp/" examples and command lines, filtered as the repository's before-stop check
#     does, and mkdtemp templates XXXXXX), report wording (a helper's report header, "the lead"), a clock
#     stamp "HH:MM UTC", or an equation citation in a non-canonical form ("eq. 8", "eqs. 8",
#     "eq 8", "Eq."); the one form is eq. (34), eq. (A.5), eqs. (8)–(12), eqs. (28), (30);
#  2. every equation cited as eq. (N) / eqs. (N)... in a tracked file has an entry "### (N)" in
#     docs/equations.md;
#  3. every file named on a "Code:" line of docs/equations.md exists, and every function named
#     there (written name()) occurs as "name(" in one of the files of that line.
# Prints every offending line as FILE:LINE: TEXT. No network; runs in a second or two.
set -u
cd "${NC_ROOT:-$(dirname "$0")/../..}" || exit 1
eqdoc=docs/equations.md
fail=0

if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -t files < <(git ls-files -- '*.md' '*.c' '*.h' '*.py' '*.sh')
else
  mapfile -t files < <(find . -path ./build -prune -o -path ./bin -prune -o -path ./results -prune \
    -o -type f \( -name '*.md' -o -name '*.c' -o -name '*.h' -o -name '*.py' -o -name '*.sh' \) \
    -print | sed 's|^\./||' | sort)
fi
# this test names the patterns it looks for: it is not checked against itself
self=tests/docs/test_citations.sh
checked=()
for f in "${files[@]}"; do [ "$f" = "$self" ] || [ ! -f "$f" ] || checked+=("$f"); done

report() {  # report TITLE < lines
  local lines
  lines=$(cat)
  [ -z "$lines" ] && return 0
  echo "FAIL: $1"
  printf '%s\n' "$lines" | sed 's/^/  /'
  fail=1
}

scan() {  # scan EXTENDED_REGEX -> FILE:LINE:TEXT
  grep -n -H -I -E -- "$1" "${checked[@]}" 2>/dev/null
}

# ---- 1. forbidden text ----------------------------------------------------------------------
report "pointer to source material outside the repository (shared/reference)" < <(scan 'shared/reference')
report "pointer to the removed scripts/diagnostics/ (now docs/notes/ and scripts/analysis/)" < <(
  scan 'scripts/diagnostics')

report "temporary path (/tmp/...): use mktemp, \$TMPDIR/\$NC_TMP or a results/ folder" < <(scan '/tmp/[A-Za-z0-9_]' |
  grep -v -E 'mktemp|TMPDIR|XXXXXX|(--out|--output) /tmp/|^[^:]+:[0-9]+:(scripts|bin|/usr/bin)/')

report "report wording about who worked on what" < <(scan 'Helper[ ]report|[Tt]he lead([^a-z]|$)')

report "clock stamp (HH:MM UTC)" < <(scan '[0-9]{2}:[0-9]{2} UTC')

report "non-canonical equation citation (write eq. (8), eqs. (8)–(12), eqs. (28), (30))" < <(
  scan '(^|[^-A-Za-z])(eqs?\. [0-9]|eq [0-9])|Eq\.')

# ---- 2. cited equations are documented ------------------------------------------------------
if [ ! -f "$eqdoc" ]; then
  echo "FAIL: $eqdoc is missing"
  exit 1
fi
documented=$(sed -n 's/^### (\([0-9A.]*\)).*/\1/p' "$eqdoc" | sort -u)
# each citation "eq. (N)" or "eqs. (N)–(M), (K) and (L)" -> FILE:LINE:N for every number in it
missing=$(grep -n -H -I -o -E 'eqs?\. \([0-9A.]+\)([ ]*(,|–|-|and|or|to)[ ]*\([0-9A.]+\))*' \
            "${checked[@]}" 2>/dev/null |
          while IFS= read -r hit; do
            loc=${hit%%:eq*}; cite=${hit#"$loc":}
            for n in $(printf '%s\n' "$cite" | grep -o -E '\([0-9A.]+\)' | tr -d '()'); do
              grep -qx -F -- "$n" <<<"$documented" || echo "$loc: eq. ($n) has no entry '### ($n)' in $eqdoc"
            done
          done)
report "equation cited but not listed in $eqdoc" <<<"$missing"

# ---- 3. Code: lines name existing files and functions --------------------------------------
stale=$(grep -n -E '^Code:' "$eqdoc" | while IFS= read -r row; do
  ln=${row%%:*}; text=${row#*:}
  paths=$(printf '%s\n' "$text" | grep -o -E '`[A-Za-z0-9_./-]+\.(c|h|py|sh|json|md)`' | tr -d '`')
  funcs=$(printf '%s\n' "$text" | grep -o -E '`[A-Za-z_][A-Za-z0-9_]*\(\)`' | tr -d '`()')
  [ -n "$paths" ] || echo "$eqdoc:$ln: Code: line names no file"
  for p in $paths; do [ -f "$p" ] || echo "$eqdoc:$ln: $p does not exist"; done
  for fn in $funcs; do
    found=0
    for p in $paths; do [ -f "$p" ] && grep -q -E "(^|[^A-Za-z0-9_])$fn\(" "$p" && found=1 && break; done
    [ $found -eq 1 ] || echo "$eqdoc:$ln: $fn() is not in $(echo $paths)"
  done
done)
report "stale file or function on a Code: line of $eqdoc" <<<"$stale"

if [ $fail -eq 0 ]; then
  echo "citations, paths and the equation list are consistent (${#checked[@]} files)"
fi
exit $fail
