#include "core/option_registry.h"

#include <cmath>

#include <fmt/format.h>

namespace segslam {

std::string FormatOptionValue(double value) {
  if (std::isfinite(value) && value == std::floor(value) && std::abs(value) < 1e15) {
    return fmt::format("{}", static_cast<long long>(value));
  }
  return fmt::format("{}", value);
}

std::string DescribeOptionRange(const OptionRange& range, OptionKind kind) {
  if (kind == OptionKind::kSwitch) return "0 or 1";
  const bool low = std::isfinite(range.min);
  const bool high = std::isfinite(range.max);
  if (low && high) {
    return fmt::format("{}{}, {}{}", range.min_open ? "(" : "[", FormatOptionValue(range.min),
                       FormatOptionValue(range.max), range.max_open ? ")" : "]");
  }
  if (low) return fmt::format("{} {}", range.min_open ? ">" : ">=", FormatOptionValue(range.min));
  if (high) return fmt::format("{} {}", range.max_open ? "<" : "<=", FormatOptionValue(range.max));
  return "any";
}

nlohmann::json OptionValueJson(double value, OptionKind kind) {
  switch (kind) {
    case OptionKind::kSwitch: return value != 0;
    case OptionKind::kWholeNumber: return static_cast<long long>(value);
    case OptionKind::kReal: return value;
  }
  return value;
}

double ReportedValue(float value) { return std::stod(fmt::format("{}", value)); }

}  // namespace segslam
