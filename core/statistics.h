// Summary statistics shared by the evaluation code.
#pragma once

#include <vector>

namespace segslam {

// The median as numpy computes it: the middle value, or the mean of the two middle
// values for an even count; NaN for no values. The values must not hold NaN (sorting
// them is undefined): throws std::invalid_argument if they do. Callers that use NaN for
// "no value" drop those first (as the repeat spreads do).
double Median(std::vector<double> values);

}  // namespace segslam
