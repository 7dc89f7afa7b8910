// "NAME=VALUE" option overrides from the command line and scenario files (seg-eval
// --segmenter-option and --refiner, run --tracker and --refiner, bench.tracker and
// bench.refiner): the split, the number and the table of settable fields, with one
// wording of errors.
#pragma once

#include <map>
#include <string>
#include <utility>
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

// The fields of an options struct that can be set by name, each with a setter that reads
// the parsed value (WholeNumberValue and ZeroOrOneValue check integers and booleans).
template <typename Options>
class NamedOptionTable {
 public:
  using Setter = void (*)(Options*, const NumericAssignment&);

  // `what` names the options in messages, e.g. "tracker option".
  NamedOptionTable(std::string what, std::map<std::string, Setter> setters)
      : what_(std::move(what)), setters_(std::move(setters)) {}

  // Sets one field from "name=value"; throws segslam::Error naming the field on an
  // unknown name or a malformed value, leaving `options` as it was.
  void Set(Options* options, const std::string& assignment) const {
    const NumericAssignment parsed = ParseNumericAssignment(assignment, what_);
    const auto setter = setters_.find(parsed.name);
    if (setter == setters_.end()) ThrowUnknownOption(what_, parsed.name, Names());
    setter->second(options, parsed);
  }

  // The names Set accepts, sorted.
  std::vector<std::string> Names() const {
    std::vector<std::string> names;
    for (const auto& entry : setters_) names.push_back(entry.first);
    return names;  // std::map keeps them sorted
  }

 private:
  std::string what_;
  std::map<std::string, Setter> setters_;
};

}  // namespace segslam
