// Summary statistics shared by the evaluation code.
#pragma once

#include <cstddef>
#include <vector>

namespace segslam {

// The median as numpy computes it: the middle value, or the mean of the two middle
// values for an even count; NaN for no values. The values must not hold NaN (sorting
// them is undefined): throws std::invalid_argument if they do. Callers that use NaN for
// "no value" drop those first (as the repeat spreads do).
double Median(std::vector<double> values);

// The value std::nth_element puts at index k (the k-th smallest, from 0), found by a
// histogram of the values' bits: positive floats order as their bit patterns do, so one
// pass finds the bucket that holds rank k and only that bucket's values are selected
// among, which takes a fraction of nth_element's time on many values. Values outside
// (0, inf) are selected by std::nth_element instead; NaN is not allowed. `values` serves
// as scratch: its contents are left unspecified. Throws std::invalid_argument when k is
// not below the count.
float KthSmallest(std::vector<float>* values, std::size_t k);
// The same over the n values at `values`.
float KthSmallest(float* values, std::size_t n, std::size_t k);

}  // namespace segslam
