#include "harness/cli.h"

#include <malloc.h>

#include <cstdio>

int main(int argc, char** argv) {
#ifndef __SANITIZE_ADDRESS__  // AddressSanitizer's allocator replaces glibc's and has no such thresholds.
  // Every frame allocates and frees several image-sized buffers (rendering, noise, PNG
  // encoding). With glibc's default thresholds each is a fresh mmap whose pages fault
  // in again on every frame: a fifth of generation time went to page faults. Keeping
  // such blocks in the heap removes that. 32 MiB is the most mallopt(3) documents on
  // 64-bit (Debian 12's glibc 2.36 accepts more, older versions refuse it) and far above
  // a frame's buffers (a 640x480 float image is 1.2 MB).
  // Setting the trim threshold also turns glibc's dynamic mmap threshold off: alone, it
  // would pin that at 128 KiB, so it is set only once the mmap threshold is.
  if (mallopt(M_MMAP_THRESHOLD, 32 << 20) != 1) {
    std::fprintf(stderr, "segslam: warning: mallopt(M_MMAP_THRESHOLD) refused; image buffers stay mmapped\n");
  } else if (mallopt(M_TRIM_THRESHOLD, 256 << 20) != 1) {
    std::fprintf(stderr, "segslam: warning: mallopt(M_TRIM_THRESHOLD) refused\n");
  }
#endif
  return segslam::harness::RunCli(argc, argv);
}
