// Summary statistics shared by the evaluation code.
#pragma once

#include <vector>

namespace segslam {

// The median as numpy computes it: the middle value, or the mean of the two middle
// values for an even count; NaN for no values.
double Median(std::vector<double> values);

}  // namespace segslam
