#include "core/option_assignment.h"

#include <cctype>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "core/pose.h"

namespace segslam {

NumericAssignment ParseNumericAssignment(const std::string& assignment, const std::string& what) {
  const std::size_t eq = assignment.find('=');
  if (eq == std::string::npos) throw Error(what + ": expected NAME=VALUE, got '" + assignment + "'");
  NumericAssignment parsed;
  parsed.name = assignment.substr(0, eq);
  parsed.text = assignment.substr(eq + 1);
  // ParseTumNumber refuses NaN, inf, hex and trailing characters, but strtod beneath it
  // skips leading white space: refuse that here, so " 5" is not silently 5.
  if (parsed.text.empty() || std::isspace(static_cast<unsigned char>(parsed.text.front())) ||
      !ParseTumNumber(parsed.text, &parsed.value)) {
    throw Error(what + " " + parsed.name + ": not a number: '" + parsed.text + "'");
  }
  return parsed;
}

int WholeNumberValue(const NumericAssignment& parsed, const std::string& what) {
  if (parsed.value != std::floor(parsed.value) || parsed.value < std::numeric_limits<int>::min() ||
      parsed.value > std::numeric_limits<int>::max()) {
    throw Error(what + " " + parsed.name + ": not a whole number: '" + parsed.text + "'");
  }
  return static_cast<int>(parsed.value);
}

bool ZeroOrOneValue(const NumericAssignment& parsed, const std::string& what) {
  if (parsed.value != 0 && parsed.value != 1) {
    throw Error(what + " " + parsed.name + ": expected 0 or 1, got '" + parsed.text + "'");
  }
  return parsed.value == 1;
}

void ThrowUnknownOption(const std::string& what, const std::string& name, const std::vector<std::string>& known) {
  std::string list;
  for (const std::string& field : known) list += (list.empty() ? "" : ", ") + field;
  throw Error(what + ": unknown field '" + name + "' (known: " + list + ")");
}

}  // namespace segslam
