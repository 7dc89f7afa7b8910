// "NAME=VALUE" option overrides from the command line (seg-eval --segmenter-option and
// --refiner, run --tracker): the split and the number, with one wording of errors.
#pragma once

#include <string>

namespace segslam {

struct NumericAssignment {
  std::string name;
  std::string text;  // the value as written, for messages
  double value = 0;
};

// Splits "name=value" and parses the value as a whole number string (no trailing
// characters). Throws segslam::Error "<what>: expected NAME=VALUE, got '<assignment>'" or
// "<what> <name>: not a number: '<value>'".
NumericAssignment ParseNumericAssignment(const std::string& assignment, const std::string& what);

// The value of an integer or boolean option. Throw segslam::Error "<what> <name>: not a
// whole number" or "<what> <name>: expected 0 or 1".
int WholeNumberValue(const NumericAssignment& parsed, const std::string& what);
bool ZeroOrOneValue(const NumericAssignment& parsed, const std::string& what);

}  // namespace segslam
