// Small helpers over strings: joining them with a separator, splitting text at a
// character, asking whether a list holds a value, and making text safe to print.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
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

// `message` as it may reach a terminal: printable ASCII and well-formed UTF-8 (a folder
// named in another script) as they are, every other byte (control bytes, C1 controls,
// broken UTF-8) as \xNN, so that no file's bytes clear the screen or move the cursor.
// The CLI passes every message through it before printing.
std::string TerminalSafe(std::string_view message);

// `text` (read from a file or given on the command line) as a message quotes it:
// TerminalSafe, cut after `max_chars` characters with "...".
std::string PrintableText(std::string_view text, std::size_t max_chars = 60);

}  // namespace segslam
