#include "harness/cli.h"

int main(int argc, char** argv) { return segslam::harness::RunCli(argc, argv); }
