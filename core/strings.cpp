// Joining, splitting and searching lists of strings (core/strings.h).
#include "core/strings.h"

#include <algorithm>

namespace segslam {

std::string Join(const std::vector<std::string>& parts, const std::string& separator) {
  std::string text;
  for (std::size_t i = 0; i < parts.size(); ++i) text += (i ? separator : "") + parts[i];
  return text;
}

std::vector<std::string> Split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  while (true) {
    const std::size_t end = text.find(separator, start);
    parts.push_back(text.substr(start, end == std::string::npos ? std::string::npos : end - start));
    if (end == std::string::npos) return parts;
    start = end + 1;
  }
}

bool Contains(const std::vector<std::string>& list, const std::string& value) {
  return std::find(list.begin(), list.end(), value) != list.end();
}

std::string TerminalSafe(std::string_view message) {
  static const char kHex[] = "0123456789abcdef";
  std::string safe;
  for (std::size_t i = 0; i < message.size();) {
    const auto byte = static_cast<unsigned char>(message[i]);
    std::size_t length = 0;  // of a printable character starting at i; 0: escape the byte
    if (byte >= 0x20 && byte < 0x7f) {
      length = 1;
    } else if (byte >= 0xc2 && byte <= 0xf4) {
      const std::size_t n = byte < 0xe0 ? 2 : byte < 0xf0 ? 3 : 4;
      char32_t code = byte & (0x7f >> n);
      bool well_formed = i + n <= message.size();
      for (std::size_t k = 1; well_formed && k < n; ++k) {
        const auto next = static_cast<unsigned char>(message[i + k]);
        well_formed = (next & 0xc0) == 0x80;
        code = (code << 6) | (next & 0x3f);
      }
      // Not C1 controls (U+0080 to U+009F), overlong forms, surrogates or beyond U+10FFFF.
      const char32_t lowest = n == 2 ? 0xa0 : n == 3 ? 0x800 : 0x10000;
      if (well_formed && code >= lowest && code <= 0x10ffff && !(code >= 0xd800 && code <= 0xdfff)) length = n;
    }
    if (length > 0) {
      safe.append(message.substr(i, length));
      i += length;
    } else {
      safe += {'\\', 'x', kHex[byte >> 4], kHex[byte & 0xf]};
      ++i;
    }
  }
  return safe;
}

std::string PrintableText(std::string_view text, std::size_t max_chars) {
  // Cut after max_chars characters (a well-formed UTF-8 sequence is one, any other byte
  // one), never inside a character.
  std::size_t end = 0;
  for (std::size_t chars = 0; end < text.size() && chars < max_chars; ++chars) {
    const auto byte = static_cast<unsigned char>(text[end]);
    std::size_t length = byte >= 0xc2 && byte <= 0xf4 ? (byte < 0xe0 ? 2 : byte < 0xf0 ? 3 : 4) : 1;
    for (std::size_t k = 1; k < length; ++k) {
      if (end + k >= text.size() || (static_cast<unsigned char>(text[end + k]) & 0xc0) != 0x80) length = 1;
    }
    end += length;
  }
  return TerminalSafe(text.substr(0, end)) + (end < text.size() ? "..." : "");
}

}  // namespace segslam
