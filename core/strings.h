// Small helpers over lists of strings: joining them with a separator, splitting text at a
// character, and asking whether a list holds a value.
#pragma once

#include <string>
#include <vector>

namespace segslam {

// The parts with `separator` between each two, as Python's str.join: {} -> "",
// {"a"} -> "a", {"a", "", "b"} with ", " -> "a, , b".
std::string Join(const std::vector<std::string>& parts, const std::string& separator);

// The pieces of `text` between occurrences of `separator`, empty pieces kept: "a,,b" ->
// {"a", "", "b"}, "" -> {""}, "a," -> {"a", ""}. Join(Split(t, c), std::string(1, c)) == t.
std::vector<std::string> Split(const std::string& text, char separator);

// Whether `list` holds `value`.
bool Contains(const std::vector<std::string>& list, const std::string& value);

}  // namespace segslam
