#!/usr/bin/env bash
# The benchmarks, one driver: scripts/bench.sh COMMAND [ARGS...]
#
# Each command measures one stage, or compares the current tree with an earlier commit (the ab
# commands: OLD_COMMIT first, built in a git worktree under out/ab/, the two builds alternated in
# one run), prints its table and writes it into its section of BENCHMARKS.md (or docs/) with the
# command that made it. `scripts/bench.sh help` lists the commands, `scripts/bench.sh help
# COMMAND` shows one's usage. The commands live in scripts/bench/COMMAND.sh, sourced here with
# their arguments after the helpers below; they source scripts/bench-setup.sh (dependencies, a
# Release build, the generated scenes, the old build) themselves, since some ask it for more.
set -euo pipefail
cd "$(dirname "$0")/.."
here=scripts/bench

usage() {
  echo "Usage: scripts/bench.sh COMMAND [ARGS...]   (scripts/bench.sh help COMMAND: its usage)"
  echo
  echo "Commands:"
  local f
  for f in "$here"/*.sh; do
    # The first sentence of the file's first comment line.
    printf '  %-16s %s\n' "$(basename "$f" .sh)" "$(sed -n '1s/^# //p' "$f" | cut -c1-100)"
  done
}

command="${1:-help}"
[ $# -gt 0 ] && shift
case "$command" in
  help | -h | --help)
    if [ $# -gt 0 ]; then
      [ -f "$here/$1.sh" ] || { echo "bench.sh: no command '$1'" >&2; usage >&2; exit 2; }
      sed -n '/^#/!q; s/^# \{0,1\}//p' "$here/$1.sh"
    else
      usage
    fi
    exit 0
    ;;
esac
if [ ! -f "$here/$command.sh" ]; then
  echo "bench.sh: no command '$command'" >&2
  usage >&2
  exit 2
fi
if [[ "$command" == ab || "$command" == ab-* ]]; then
  old="${1:?usage: scripts/bench.sh $command OLD_COMMIT ... (scripts/bench.sh help $command)}"
  git rev-parse --verify -q "$old^{commit}" >/dev/null || { echo "bench.sh: '$old' is no commit" >&2; exit 2; }
fi

# ---- helpers the commands share ----

# ab_alternate RUNS STEP: for each of RUNS rounds, `STEP old ROUND` then `STEP new ROUND`: the two
# builds alternate, so that drift (heat, other load) falls on both.
ab_alternate() {
  local runs=$1 step=$2 round side
  for round in $(seq "$runs"); do
    for side in old new; do "$step" "$side" "$round"; done
  done
}

# ab_record TSV SIDE WHAT VALUE: one measurement, a row of the TSV ab_table reads.
ab_record() { printf '%s\t%s\t%s\n' "$2" "$3" "$4" >>"$1"; }

# ab_time TSV SIDE WHAT COMMAND...: runs COMMAND (its output to $dir/ab-last.out) and records its
# wall-clock seconds.
ab_time() {
  local tsv=$1 side=$2 what=$3 start end
  shift 3
  start=$(date +%s.%N)
  "$@" >"$dir/ab-last.out"
  end=$(date +%s.%N)
  ab_record "$tsv" "$side" "$what" "$(python3 -c "print($end - $start)")"
}

# ab_table TSV SECTION COMMAND TITLE: the medians of every quantity of the TSV, old against new with
# each run's value and their ratio (scripts/vctables.py ab-medians), printed and written into
# BENCHMARKS.md's SECTION with COMMAND (nothing written when SECTION is "-").
ab_table() {
  local tsv=$1 section=$2 cmd=$3 title=$4
  python3 scripts/vctables.py ab-medians "$tsv" "$title" >"$tsv.md"
  [ "$section" = - ] || python3 scripts/vctables.py replace-section BENCHMARKS.md "$section" "$cmd" "$tsv.md"
  cat "$tsv.md"
}

# same_files A B WHAT: "WHAT: byte-identical" or "WHAT: differ".
same_files() { if cmp -s "$1" "$2"; then echo "$3: byte-identical"; else echo "$3: differ"; fi; }

# shellcheck disable=SC1090
source "$here/$command.sh" "$@"
