// Default run-time options of the sanitizers, compiled into every executable of a
// SEGSLAM_SANITIZE=ON build (cmake/Sanitizers.cmake). The sanitizer run-times call these
// functions at start-up; environment variables given by a user still take precedence.

extern "C" {

// AddressSanitizer: leak detection on, and the process exits non-zero on the first error.
// intercept_tls_get_addr=0: GCC 12's run-time takes a dynamic TLS block whose address is
// 16 past a page boundary for a glibc <= 2.18 header and reads the two words before it as
// a range; Mesa's driver (dlopen'ed, dynamic TLS) lands there by chance, and the leak
// check at exit then dies with "Tracer caught signal 11" (seen in CI on `generate`).
// Without the interceptor the check still reaches those blocks: glibc mallocs them and
// the thread's DTV, which the scan of static TLS finds, points at them.
const char* __asan_default_options() {
  return "detect_leaks=1:abort_on_error=0:halt_on_error=1:strict_string_checks=1:"
         "detect_stack_use_after_return=0:check_initialization_order=1:"
         "intercept_tls_get_addr=0";
}

// LeakSanitizer: suppressions for third-party libraries only (see the file's comments).
const char* __lsan_default_options() {
  return "suppressions=" SEGSLAM_LSAN_SUPPRESSIONS ":print_suppressions=0";
}

// UndefinedBehaviorSanitizer: a stack trace with every report (the build makes every
// report fatal with -fno-sanitize-recover=undefined).
const char* __ubsan_default_options() { return "print_stacktrace=1:halt_on_error=1"; }

}  // extern "C"
