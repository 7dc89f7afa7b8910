#include "harness/cli.h"

#include <malloc.h>

int main(int argc, char** argv) {
  // Every frame allocates and frees several image-sized buffers (rendering, noise, PNG
  // encoding). With glibc's default thresholds each is a fresh mmap whose pages fault
  // in again on every frame: a fifth of generation time went to page faults. Keeping
  // such blocks in the heap removes that.
  mallopt(M_MMAP_THRESHOLD, 64 << 20);
  mallopt(M_TRIM_THRESHOLD, 256 << 20);
  return segslam::harness::RunCli(argc, argv);
}
