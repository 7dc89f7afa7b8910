// Proof that a SEGSLAM_SANITIZE=ON build really checks: each mode commits one error that
// the sanitizers must report, and CTest (cmake/Sanitizers.cmake) expects the report. A
// build whose flags were lost, or whose LeakSanitizer suppressions swallowed segslam's
// own leaks, or whose UBSan only warns, fails these tests.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace {

// Kept out of the optimizer's sight, so that the errors below happen at run time.
volatile int g_index = 8;
volatile int g_large = 2147483647;
int* volatile g_leaked = nullptr;

int HeapOverflow() {
  int* values = new int[8];
  std::memset(values, 0, (g_index + 1) * sizeof(int));  // one int past the end
  const int result = values[0];
  delete[] values;
  return result;
}

int SignedOverflow() {
  const int a = g_large;
  const int b = a + 1;  // undefined behaviour: int overflow
  std::printf("UBSAN-NOT-FATAL: the program went on after undefined behaviour (%d)\n", b);
  return 0;
}

int Leak() {
  g_leaked = new int[100];
  g_leaked[0] = 1;
  g_leaked = nullptr;  // the only pointer to the block is gone
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "heap-overflow") return HeapOverflow();
  if (mode == "signed-overflow") return SignedOverflow();
  if (mode == "leak") return Leak();
  std::fprintf(stderr, "usage: sanitizer_canary heap-overflow|signed-overflow|leak\n");
  return 2;
}
