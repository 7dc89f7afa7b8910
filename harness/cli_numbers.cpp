#include "harness/cli_numbers.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>

#include <fmt/format.h>

#include "core/error.h"

namespace segslam::harness {

CLI::Validator WholeNumberIn(long long min, long long max, const std::string& meaning) {
  const std::string range =
      fmt::format("a whole number from {} to {}{}", min, max, meaning.empty() ? "" : " (" + meaning + ")");
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        errno = 0;
        char* end = nullptr;
        const long long value = std::strtoll(text.c_str(), &end, 10);
        const bool whole = !text.empty() && end == text.c_str() + text.size() && errno == 0;
        if (whole && value >= min && value <= max) return "";
        return "must be " + range + ", got " + PrintableText(text);
      },
      fmt::format("{}..{}", min, max));
}

CLI::Validator NumberIn(double min, double max, bool min_excluded) {
  const std::string range = min_excluded ? fmt::format("a number above {:g} and at most {:g}", min, max)
                                         : fmt::format("a number from {:g} to {:g}", min, max);
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        char* end = nullptr;
        const double value = std::strtod(text.c_str(), &end);
        const bool number = !text.empty() && end == text.c_str() + text.size() && std::isfinite(value);
        if (number && (min_excluded ? value > min : value >= min) && value <= max) return "";
        return "must be " + range + ", got " + PrintableText(text);
      },
      fmt::format("{}{:g}..{:g}", min_excluded ? ">" : "", min, max));
}

}  // namespace segslam::harness
