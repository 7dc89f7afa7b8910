// Checks of the CLI's numeric options whose refusals say the allowed range in words:
// "--frames: must be a whole number from 0 to 1000000 (0 = all), got -3". CLI11's own
// print a double's range in full (a 309-digit maximum) and refuse a number too large for
// the field as a conversion error that names no range. The value is checked as text,
// before CLI11 converts it, so no value can overflow the field first.
#pragma once

#include <string>

#include <CLI/CLI.hpp>

namespace segslam::harness {

// Frames of a sequence or a dataset's pass: a bound well above any sequence (TUM's longest
// has some 20000), below what would overflow a frame counter.
constexpr long long kMaxFrames = 1000000;
// Repeats of a run (the paper uses 10).
constexpr long long kMaxRepeats = 1000;
// Threads, or runs at a time.
constexpr long long kMaxThreads = 1024;

// A whole number in [min, max]; `meaning`, when given, is added in parentheses
// ("0 = all").
CLI::Validator WholeNumberIn(long long min, long long max, const std::string& meaning = "");

// A finite number in [min, max], or in (min, max] where `min_excluded`.
CLI::Validator NumberIn(double min, double max, bool min_excluded = false);

}  // namespace segslam::harness
