#include "core/option_assignment.h"

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

}  // namespace segslam
