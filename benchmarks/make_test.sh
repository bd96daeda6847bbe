#!/usr/bin/env bash
# How long a newcomer waits for the README's second command: `make test` on a fresh clone of
# this repository's HEAD, installation included, with empty caches (no pip wheel of carom, no
# compiled kernel, no matplotlib font cache: XDG_CACHE_HOME and the kernel cache point at an
# empty folder), started from a background shell that ignores SIGINT, as `make test &`, nohup
# and schedulers start it (issue 42).
#
#   bash benchmarks/make_test.sh [WORKDIR]
#   TARGET=demo bash benchmarks/make_test.sh [WORKDIR]    # the first command, `make demo`
#
# Prints the wall-clock seconds and make's exit code; the log is WORKDIR/make-TARGET.log.
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
work="${1:-$(mktemp -d)}"
target="${TARGET:-test}"
rm -rf "$work/clone" "$work/cache"
mkdir -p "$work/cache"
git clone -q "$here" "$work/clone"
cd "$work/clone"
start=$(date +%s.%N)
set +e
XDG_CACHE_HOME="$work/cache" setsid bash -c "trap '' INT; make $target" </dev/null >"$work/make-$target.log" 2>&1
code=$?
set -e
end=$(date +%s.%N)
echo "commit $(git rev-parse --short HEAD): make $target exited $code after $(python3 -c "print(round($end - $start, 1))") s (log: $work/make-$target.log)"
grep -E "passed|failed|Dask workers" "$work/make-$target.log" | grep -v "^WARNING" | tail -3
