#include "core/option_assignment.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/error.h"

namespace segslam {

NumericAssignment ParseNumericAssignment(const std::string& assignment, const std::string& what) {
  const std::size_t eq = assignment.find('=');
  if (eq == std::string::npos) throw Error(what + ": expected NAME=VALUE, got '" + assignment + "'");
  NumericAssignment parsed;
  parsed.name = assignment.substr(0, eq);
  parsed.text = assignment.substr(eq + 1);
  try {
    std::size_t used = 0;
    parsed.value = std::stod(parsed.text, &used);
    if (used != parsed.text.size()) throw std::invalid_argument(parsed.text);
  } catch (const std::exception&) {
    throw Error(what + " " + parsed.name + ": not a number: '" + parsed.text + "'");
  }
  return parsed;
}

int WholeNumberValue(const NumericAssignment& parsed, const std::string& what) {
  if (parsed.value != std::floor(parsed.value) || std::abs(parsed.value) > std::numeric_limits<int>::max()) {
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
