// "NAME=VALUE" option overrides from the command line and scenario files (seg-eval
// --segmenter-option and --refiner, run --tracker and --refiner, bench.tracker and
// bench.refiner): the split and the number, with one
// wording of errors (core/option_registry.h declares the options themselves).
#pragma once

#include <string>
#include <vector>

namespace segslam {

struct NumericAssignment {
  std::string name;
  std::string text;  // the value as written, for messages
  double value = 0;
};

// Splits "name=value" and parses all of the value as a finite number in decimal or
// scientific notation (as ParseTumNumber in core/pose.h: no NaN, inf, hex, white space
// or trailing characters). Throws segslam::Error "<what>: expected NAME=VALUE, got
// '<assignment>'" or "<what> <name>: not a number: '<value>'".
NumericAssignment ParseNumericAssignment(const std::string& assignment, const std::string& what);

// The value of an integer or boolean option. Throw segslam::Error "<what> <name>: not a
// whole number" (also outside int's range) or "<what> <name>: expected 0 or 1".
int WholeNumberValue(const NumericAssignment& parsed, const std::string& what);
bool ZeroOrOneValue(const NumericAssignment& parsed, const std::string& what);

// Throws segslam::Error "<what>: unknown field '<name>' (known: a, b, ...)".
[[noreturn]] void ThrowUnknownOption(const std::string& what, const std::string& name,
                                     const std::vector<std::string>& known);

}  // namespace segslam
