// Default run-time options of the sanitizers, compiled into every executable of a
// SEGSLAM_SANITIZE=ON build (cmake/Sanitizers.cmake). The sanitizer run-times call these
// functions at start-up; environment variables given by a user still take precedence.

extern "C" {

// AddressSanitizer: leak detection on, and the process exits non-zero on the first error.
const char* __asan_default_options() {
  return "detect_leaks=1:abort_on_error=0:halt_on_error=1:strict_string_checks=1:"
         "detect_stack_use_after_return=0:check_initialization_order=1";
}

// LeakSanitizer: suppressions for third-party libraries only (see the file's comments).
const char* __lsan_default_options() {
  return "suppressions=" SEGSLAM_LSAN_SUPPRESSIONS ":print_suppressions=0";
}

// UndefinedBehaviorSanitizer: a stack trace with every report (the build makes every
// report fatal with -fno-sanitize-recover=undefined).
const char* __ubsan_default_options() { return "print_stacktrace=1:halt_on_error=1"; }

}  // extern "C"
