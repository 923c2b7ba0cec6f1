#!/usr/bin/env bash
# Run the test suite N times in a row while busy loops hog the CPU cores (docs/testing.md, "The stress run").
#
#   tools/stress_tests.sh [-n PASSES] [-j HOGS] [-- PYTEST ARGS...]
#
#   -n PASSES   consecutive passes of the suite (default 3); stops at the first failing pass
#   -j HOGS     busy-loop processes started beside the tests (default 2: both cores of a
#               2-core machine; use `nproc` to hog every core of a bigger one)
#   PYTEST ARGS replace the default selection, e.g.  -- tests/frontends/test_tui.py
#
# The command is the README's: .venv/bin/python -m pytest (the fast suite; slow tests stay
# deselected by pyproject.toml).  The hogs are stopped on exit, including Ctrl-C and errors.
# Prints each pass's wall time and the load average, then a verdict; exit 0 only when
# every pass passed.
set -u

passes=3
hogs=2
while getopts "n:j:h" opt; do
    case "$opt" in
        n) passes=$OPTARG ;;
        j) hogs=$OPTARG ;;
        h) sed -n '2,14p' "$0"; exit 0 ;;
        *) echo "usage: $0 [-n PASSES] [-j HOGS] [-- PYTEST ARGS...]" >&2; exit 2 ;;
    esac
done
shift $((OPTIND - 1))
case "$passes$hogs" in *[!0-9]*|"") echo "-n and -j take whole numbers" >&2; exit 2 ;; esac

cd "$(dirname "$0")/.." || exit 2
python=.venv/bin/python
[ -x "$python" ] || { echo "no $python: create the virtualenv first (see README)" >&2; exit 2; }

hog_pids=()
stop_hogs() {
    for pid in "${hog_pids[@]}"; do
        kill "$pid" 2>/dev/null
    done
    for pid in "${hog_pids[@]}"; do
        wait "$pid" 2>/dev/null
    done
    hog_pids=()
}
trap stop_hogs EXIT
trap 'exit 130' INT TERM

for _ in $(seq 1 "$hogs"); do
    ( while :; do :; done ) &   # one busy loop: a full core
    hog_pids+=($!)
done
echo "stress: $hogs busy loop(s) running (pids ${hog_pids[*]:-none}), $passes pass(es) of: $python -m pytest -q $*"

failed=0
for i in $(seq 1 "$passes"); do
    start=$(date +%s.%N)
    "$python" -m pytest -q -p no:cacheprovider "$@"
    rc=$?
    end=$(date +%s.%N)
    load=$(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || echo "?")
    printf 'stress: pass %d/%d %s in %.1f s (load average %s)\n' "$i" "$passes" \
        "$([ "$rc" -eq 0 ] && echo passed || echo "FAILED (pytest exit $rc)")" \
        "$(awk -v a="$start" -v b="$end" 'BEGIN{print b-a}')" "$load"
    if [ "$rc" -ne 0 ]; then
        failed=$i
        break
    fi
done

stop_hogs
if [ "$failed" -eq 0 ]; then
    echo "stress: VERDICT PASS - $passes consecutive pass(es) under $hogs busy loop(s)"
    exit 0
fi
echo "stress: VERDICT FAIL - pass $failed of $passes failed under $hogs busy loop(s)"
exit 1
