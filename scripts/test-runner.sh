#!/usr/bin/env bash
# Cargo's runner for every binary it runs on Linux (.cargo/config.toml). A test binary (target/<profile>/deps/…)
# gets each of its tests run in a process of its own, STRATA_TEST_JOBS at a time (default: the CPU count);
# anything else (`cargo run`, examples, benches, libtest options this script does not know) runs as it is.
#
# Why: the Khronos validation layer Debian 12 ships keeps state shared between instances without a lock
# (Vulkan-ValidationLayers #4391), so within one process GPU tests take turns (tests/common/mod.rs), and plain
# `cargo test` left all but one core idle through every render and every cold pipeline compile (single-threaded
# in lavapipe). Separate processes share nothing but Mesa's on-disk shader cache, which is made for that.
# Measured in docs/performance.md ("Speed at equal error", the test suite). STRATA_TEST_JOBS=1 runs the binary
# as libtest alone would.
set -uo pipefail

bin=$1
shift
# `wait -n -p` needs bash 5.1 (Debian 12 and Ubuntu 22.04 have it).
[[ $(basename "$(dirname "$bin")") == deps && ${STRATA_TEST_JOBS:-} != 1 ]] || exec "$bin" "$@"
((BASH_VERSINFO[0] * 100 + BASH_VERSINFO[1] >= 501)) || exec "$bin" "$@"

# The libtest arguments this script understands; with any other, libtest runs the binary itself.
list_args=()
child_args=()
show_output=0
for ((i = 1; i <= $#; i++)); do
    arg=${!i}
    case $arg in
        --nocapture | --show-output) child_args+=("$arg"); show_output=1 ;;
        --ignored | --include-ignored) list_args+=("$arg"); child_args+=("$arg") ;;
        --exact | --skip=*) list_args+=("$arg") ;;
        --skip) ((i++)); list_args+=("$arg" "${!i:-}") ;;
        -q | --quiet) ;;
        -*) exec "$bin" "$@" ;;
        *) list_args+=("$arg") ;;
    esac
done

listing=$("$bin" --list --format terse "${list_args[@]}") || exec "$bin" "$@"
mapfile -t tests < <(sed -n 's/: test$//p' <<<"$listing")
((${#tests[@]} > 1)) || exec "$bin" "$@"

jobs=${STRATA_TEST_JOBS:-$(nproc 2>/dev/null || echo 2)}
[[ $jobs =~ ^[1-9][0-9]*$ ]] || { echo "STRATA_TEST_JOBS must be a positive whole number, not '$jobs'" >&2; exit 2; }
logs=$(mktemp -d "${TMPDIR:-/tmp}/strata-tests.XXXXXX") || exit 2
declare -A index_of_pid=()
started=()
trap 'kill "${!index_of_pid[@]}" 2>/dev/null; rm -rf "$logs"; exit 130' INT TERM
trap 'rm -rf "$logs"' EXIT

echo
echo "running ${#tests[@]} tests, each in its own process, $jobs at a time (scripts/test-runner.sh)"
start=$SECONDS
passed=0
ignored=0
failed=()
# A test whose process failed with a crash inside native code (the handler's "strata: crashed with SIG…", from
# the test's own process or a `strata` it ran) runs once more: lavapipe and the validation layer crash now and then
# (five crashes on record in dozens of full runs, one inside the layer on heap memory something had overwritten),
# never twice in a row (README, "Tests"). The first run's log is kept and its crash is printed at the end either way;
# a second crash fails.
crash_marker='strata: crashed with SIG'
declare -A crashed_once=()
rerun=-1

# Reports the test whose process `pid` ended with status `status`.
finish() {
    local pid=$1 status=$2
    local i=${index_of_pid[$pid]}
    unset "index_of_pid[$pid]"
    local name=${tests[$i]} log=$logs/$i.log
    local took
    took=$(awk -v a="${started[$i]}" -v b="$EPOCHREALTIME" 'BEGIN { printf "%.1f s", b - a }')
    local summary
    summary=$(grep -E '^test result: ' "$log" | tail -n 1)
    if ((status != 0)) && [[ -z ${crashed_once[$i]:-} ]] && grep -q "$crash_marker" "$log"; then
        echo "test $name ... crashed inside native code (exit status $status, $took); running it once more"
        mv "$log" "$logs/$i.crash.log"
        crashed_once[$i]=1
        rerun=$i
        return
    fi
    if ((status != 0)); then
        echo "test $name ... FAILED (exit status $status, $took)"
        failed+=("$i")
    elif [[ $summary == *" 1 ignored;"* ]]; then
        echo "test $name ... ignored"
        ((ignored++))
    elif [[ $summary == *" 1 passed;"* ]]; then
        if [[ -n ${crashed_once[$i]:-} ]]; then
            echo "test $name ... ok on its second run ($took; the first run's crash is printed at the end)"
        else
            echo "test $name ... ok ($took)"
        fi
        ((passed++))
    else
        echo "test $name ... FAILED (its process ran no test: ${summary:-no summary}; $took)"
        failed+=("$i")
    fi
    if ((show_output && status == 0)); then sed 's/^/    /' "$log"; fi
}

# Each of the `jobs` workers owns a contiguous stretch of the list (the tests of a file are neighbours) and runs
# it in order; a worker whose stretch is done takes the back half of the longest one left. Tests of one file
# mostly share pipeline variants, and lavapipe compiles a variant cold for tens of seconds on one core: two
# processes that miss Mesa's cache at once both compile it, where one after the other the second finds it
# (docs/performance.md, "A stretch of the list per worker").
declare -a next_of=() end_of=() worker_of_pid=()
((jobs <= ${#tests[@]})) || jobs=${#tests[@]}
for ((w = 0; w < jobs; w++)); do
    next_of[w]=$((w * ${#tests[@]} / jobs))
    end_of[w]=$(((w + 1) * ${#tests[@]} / jobs))
done
# Starts worker `w`'s next test, if any is left.
start_next() {
    local w=$1 i longest=-1 v
    if ((next_of[w] >= end_of[w])); then
        for ((v = 0; v < jobs; v++)); do
            ((end_of[v] > next_of[v] && (longest < 0 || end_of[v] - next_of[v] > end_of[longest] - next_of[longest]))) &&
                longest=$v
        done
        ((longest >= 0)) || return 0
        next_of[w]=$((next_of[longest] + (end_of[longest] - next_of[longest]) / 2))
        end_of[w]=${end_of[longest]}
        end_of[longest]=${next_of[w]}
    fi
    i=${next_of[w]}
    next_of[w]=$((i + 1))
    start_test "$w" "$i"
}
# Starts test `i` on worker `w`.
start_test() {
    local w=$1 i=$2
    started[i]=$EPOCHREALTIME
    "$bin" --exact "${tests[$i]}" "${child_args[@]}" >"$logs/$i.log" 2>&1 &
    index_of_pid[$!]=$i
    worker_of_pid[$!]=$w
}
for ((w = 0; w < jobs; w++)); do start_next "$w"; done
while ((${#index_of_pid[@]} > 0)); do
    wait -n -p done_pid
    status=$?
    w=${worker_of_pid[$done_pid]}
    unset "worker_of_pid[$done_pid]"
    finish "$done_pid" "$status"
    if ((rerun >= 0)); then
        start_test "$w" "$rerun"
        rerun=-1
    else
        start_next "$w"
    fi
done

if ((${#failed[@]} > 0)); then
    echo
    echo "failures:"
    for i in "${failed[@]}"; do
        echo
        echo "---- ${tests[$i]} (its own process: $bin --exact '${tests[$i]}') ----"
        cat "$logs/$i.log"
    done
    echo
    echo "failures:"
    for i in "${failed[@]}"; do echo "    ${tests[$i]}"; done
fi
# Every crash last, where a CI log's tail shows it: the handler's message names the signal, the thread and the
# faulting address, and its call stack gives library and offset for `addr2line`. `show_crash I RUN LOG` prints the
# crash in LOG, run RUN of test I.
show_crash() {
    local i=$1 run=$2 log=$3
    echo
    echo "---- ${tests[$i]}, $run ----"
    grep -A 24 "$crash_marker" "$log" | head -n 40
}
crash_report=$(
    for i in "${!crashed_once[@]}"; do show_crash "$i" "first run" "$logs/$i.crash.log"; done
    for i in "${failed[@]}"; do
        if grep -q "$crash_marker" "$logs/$i.log"; then show_crash "$i" "the run that failed" "$logs/$i.log"; fi
    done
)
if [[ -n $crash_report ]]; then
    echo
    echo "crashes inside native code (a test that crashed once ran once more; a second crash failed it):"
    echo "$crash_report"
fi
echo
result=ok
((${#failed[@]} == 0)) || result=FAILED
echo "test result: $result. $passed passed; ${#failed[@]} failed; $ignored ignored; 0 measured; 0 filtered out;" \
    "finished in $((SECONDS - start)) s"
echo
((${#failed[@]} == 0)) || exit 101
