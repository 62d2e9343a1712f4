# Sourced by ci_sanitize.sh, ci_fuzz.sh and soak.sh: the sanitizer runtime
# options used everywhere, so a failure reproduces the same way by hand
# (`source scripts/sanitizer_env.sh; build-asan/bin/config_test`).
_gtrack_scripts_dir=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
# abort_on_error: a crash, not exit(1), so ctest and libFuzzer see a signal.
# detect_leaks: LSan runs at exit; driver leaks are suppressed by file below.
export ASAN_OPTIONS=${ASAN_OPTIONS:-halt_on_error=1:abort_on_error=1:detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1:print_stacktrace=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1:report_error_type=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=${_gtrack_scripts_dir}/lsan.supp:print_suppressions=0}
