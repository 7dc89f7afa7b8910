#include "harness/report_document.h"

#include <cctype>
#include <regex>
#include <system_error>

#include <fmt/format.h>

#include "core/atomic_file.h"
#include "core/error.h"

namespace segslam::harness {
namespace {

// Plain numbers (optionally signed, with exponent or a trailing '%'), which tables align
// on the right so digits line up.
bool LooksNumeric(const std::string& cell) {
  static const std::regex kNumber(R"(\s*[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?\s*%?\s*)");
  return std::regex_match(cell, kNumber);
}

std::vector<bool> NumericColumns(const ReportTable& table) {
  std::vector<bool> numeric(table.header.size(), true);
  std::vector<bool> any_value(table.header.size(), false);
  for (const auto& row : table.rows) {
    for (size_t c = 0; c < row.size(); ++c) {
      if (row[c].empty()) continue;
      any_value[c] = true;
      if (!LooksNumeric(row[c])) numeric[c] = false;
    }
  }
  for (size_t c = 0; c < numeric.size(); ++c) numeric[c] = numeric[c] && any_value[c];
  return numeric;
}

// Backslashes before what Markdown could read as syntax (CommonMark lets any ASCII
// punctuation be escaped so): emphasis, code, links, html, table pipes anywhere, and
// for a paragraph (`block_text`), block markers (#, -, +, =, "1.") at the start of a line.
// Line breaks become `line_break`.
std::string EscapeMarkdown(const std::string& text, const std::string& line_break, bool block_text = false) {
  static const std::string kInline = "\\`*_[]<>|~";
  static const std::string kLineStart = "#-+=";
  std::string out;
  out.reserve(text.size() + 8);
  bool line_start = block_text;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '\r') continue;
    if (c == '\n') {
      out += line_break;
      line_start = block_text;
      continue;
    }
    if (line_start && std::isdigit(static_cast<unsigned char>(c)) != 0) {
      // "12. " or "3) " would start an ordered list: escape the punctuation after the digits.
      size_t end = i;
      while (end < text.size() && std::isdigit(static_cast<unsigned char>(text[end])) != 0) ++end;
      out.append(text, i, end - i);
      if (end < text.size() && (text[end] == '.' || text[end] == ')')) {
        out += '\\';
        out += text[end];
        ++end;
      }
      i = end - 1;
      line_start = false;
      continue;
    }
    if (kInline.find(c) != std::string::npos || (line_start && kLineStart.find(c) != std::string::npos)) out += '\\';
    out += c;
    if (c != ' ') line_start = false;
  }
  return out;
}

// Percent-encoding for a relative URL path: unreserved characters and '/' stay.
std::string EncodeUrlPath(const std::string& path) {
  std::string out;
  for (const unsigned char c : path) {
    if (std::isalnum(c) != 0 || c == '-' || c == '.' || c == '_' || c == '~' || c == '/') {
      out += static_cast<char>(c);
    } else {
      out += fmt::format("%{:02X}", c);
    }
  }
  return out;
}

constexpr const char* kCss = R"(
body { font-family: system-ui, -apple-system, "Segoe UI", Roboto, "DejaVu Sans", sans-serif;
       color: #1f2328; background: #fff; margin: 0; }
main { max-width: 1100px; margin: 0 auto; padding: 24px 32px 64px; }
h1 { font-size: 1.8em; border-bottom: 2px solid #1f2328; padding-bottom: .3em; }
h2 { font-size: 1.35em; margin-top: 1.8em; border-bottom: 1px solid #d0d7de; padding-bottom: .2em; }
h3 { font-size: 1.15em; margin-top: 1.4em; }
h4 { font-size: 1em; margin-top: 1.2em; }
p { line-height: 1.5; white-space: pre-line; }
dl.metadata { display: grid; grid-template-columns: max-content auto; gap: 4px 18px;
              background: #f6f8fa; border: 1px solid #d0d7de; border-radius: 6px; padding: 12px 16px; }
dl.metadata dt { font-weight: 600; }
dl.metadata dd { margin: 0; font-family: ui-monospace, "DejaVu Sans Mono", monospace; font-size: .92em;
                 overflow-wrap: anywhere; }
div.table { overflow-x: auto; margin: 8px 0 28px; }
p.table-caption { font-weight: 600; margin: 0 0 8px; }
table { border-collapse: collapse; font-variant-numeric: tabular-nums; }
th, td { border: 1px solid #d0d7de; padding: 6px 12px; vertical-align: top; }
th { background: #eef1f4; text-align: left; }
tbody tr:nth-child(even) td { background: #f8f9fa; }
th.num, td.num { text-align: right; }
figure { margin: 16px 0 32px; }
figure img { max-width: 100%; height: auto; border: 1px solid #d0d7de; }
figcaption { color: #57606a; font-size: .92em; margin-top: 6px; }
)";

}  // namespace

std::string EscapeHtml(const std::string& text) {
  std::string out;
  out.reserve(text.size() + 16);
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  }
  return out;
}

ReportDocument::ReportDocument(std::string title) : title_(std::move(title)) {}

void ReportDocument::AddMetadata(std::string key, std::string value) {
  metadata_.emplace_back(std::move(key), std::move(value));
}

void ReportDocument::AddHeading(std::string text, int level) {
  if (level < 2 || level > 4) {
    throw Error(fmt::format("report '{}': heading '{}' has level {}; levels are 2..4", title_, text, level));
  }
  Block block;
  block.type = BlockType::kHeading;
  block.level = level;
  block.text = std::move(text);
  blocks_.push_back(std::move(block));
}

void ReportDocument::AddParagraph(std::string text) {
  Block block;
  block.type = BlockType::kParagraph;
  block.text = std::move(text);
  blocks_.push_back(std::move(block));
}

void ReportDocument::AddTable(ReportTable table) {
  const std::string name = table.caption.empty() ? "a table" : "table '" + table.caption + "'";
  if (table.header.empty()) throw Error(fmt::format("report '{}': {} has no columns", title_, name));
  for (size_t r = 0; r < table.rows.size(); ++r) {
    if (table.rows[r].size() != table.header.size()) {
      throw Error(fmt::format("report '{}': {} row {} has {} cells for {} columns", title_, name, r + 1,
                              table.rows[r].size(), table.header.size()));
    }
  }
  Block block;
  block.type = BlockType::kTable;
  block.table = std::move(table);
  blocks_.push_back(std::move(block));
}

void ReportDocument::AddImage(std::string relative_path, std::string caption) {
  const std::filesystem::path path(relative_path);
  bool leaves = false;
  for (const auto& part : path) leaves = leaves || part == "..";
  if (relative_path.empty() || path.is_absolute() || path.has_root_name() || relative_path.front() == '/' || leaves) {
    throw Error(fmt::format("report '{}': image path '{}' must be relative to the report's folder and stay inside it",
                            title_, relative_path));
  }
  Block block;
  block.type = BlockType::kImage;
  block.text = std::move(relative_path);
  block.caption = std::move(caption);
  blocks_.push_back(std::move(block));
}

std::string ReportDocument::ToMarkdown() const {
  std::string md = "# " + EscapeMarkdown(title_, " ") + "\n\n";
  for (const auto& [key, value] : metadata_) {
    md += fmt::format("- **{}:** {}\n", EscapeMarkdown(key, " "), EscapeMarkdown(value, " "));
  }
  if (!metadata_.empty()) md += "\n";
  for (const Block& block : blocks_) {
    switch (block.type) {
      case BlockType::kHeading:
        md += std::string(static_cast<size_t>(block.level), '#') + " " + EscapeMarkdown(block.text, " ") + "\n\n";
        break;
      case BlockType::kParagraph:
        // A backslash before a newline is CommonMark's hard line break.
        md += EscapeMarkdown(block.text, "\\\n", /*block_text=*/true) + "\n\n";
        break;
      case BlockType::kTable: {
        const ReportTable& table = block.table;
        if (!table.caption.empty()) md += "**" + EscapeMarkdown(table.caption, " ") + "**\n\n";
        const std::vector<bool> numeric = NumericColumns(table);
        const auto row_line = [](const std::vector<std::string>& cells) {
          std::string line = "|";
          for (const std::string& cell : cells) line += " " + EscapeMarkdown(cell, "<br>") + " |";
          return line + "\n";
        };
        md += row_line(table.header);
        md += "|";
        for (size_t c = 0; c < table.header.size(); ++c) md += numeric[c] ? " ---: |" : " --- |";
        md += "\n";
        for (const auto& row : table.rows) md += row_line(row);
        md += "\n";
        break;
      }
      case BlockType::kImage:
        md += fmt::format("![{}]({})\n\n", EscapeMarkdown(block.caption, " "), EncodeUrlPath(block.text));
        if (!block.caption.empty()) md += "*" + EscapeMarkdown(block.caption, " ") + "*\n\n";
        break;
    }
  }
  return md;
}

std::string ReportDocument::ToHtml() const {
  std::string html =
      "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
  html += "<title>" + EscapeHtml(title_) + "</title>\n<style>" + kCss + "</style>\n</head>\n<body>\n<main>\n";
  html += "<h1>" + EscapeHtml(title_) + "</h1>\n";
  if (!metadata_.empty()) {
    html += "<dl class=\"metadata\">\n";
    for (const auto& [key, value] : metadata_) {
      html += "<dt>" + EscapeHtml(key) + "</dt><dd>" + EscapeHtml(value) + "</dd>\n";
    }
    html += "</dl>\n";
  }
  for (const Block& block : blocks_) {
    switch (block.type) {
      case BlockType::kHeading:
        html += fmt::format("<h{0}>{1}</h{0}>\n", block.level, EscapeHtml(block.text));
        break;
      case BlockType::kParagraph:
        html += "<p>" + EscapeHtml(block.text) + "</p>\n";
        break;
      case BlockType::kTable: {
        const ReportTable& table = block.table;
        const std::vector<bool> numeric = NumericColumns(table);
        // The caption outside the table, so a long one does not wrap to the table's width.
        html += "<div class=\"table\">\n";
        if (!table.caption.empty()) html += "<p class=\"table-caption\">" + EscapeHtml(table.caption) + "</p>\n";
        html += "<table>\n";
        html += "<thead><tr>";
        for (size_t c = 0; c < table.header.size(); ++c) {
          html += (numeric[c] ? "<th class=\"num\">" : "<th>") + EscapeHtml(table.header[c]) + "</th>";
        }
        html += "</tr></thead>\n<tbody>\n";
        for (const auto& row : table.rows) {
          html += "<tr>";
          for (size_t c = 0; c < row.size(); ++c) {
            html += (numeric[c] ? "<td class=\"num\">" : "<td>") + EscapeHtml(row[c]) + "</td>";
          }
          html += "</tr>\n";
        }
        html += "</tbody>\n</table>\n</div>\n";
        break;
      }
      case BlockType::kImage:
        html += fmt::format("<figure>\n<img src=\"{}\" alt=\"{}\">\n", EscapeHtml(EncodeUrlPath(block.text)),
                            EscapeHtml(block.caption));
        if (!block.caption.empty()) html += "<figcaption>" + EscapeHtml(block.caption) + "</figcaption>\n";
        html += "</figure>\n";
        break;
    }
  }
  html += "</main>\n</body>\n</html>\n";
  return html;
}

void ReportDocument::Write(const std::filesystem::path& directory) const {
  std::error_code error;
  std::filesystem::create_directories(directory, error);
  if (error) throw FileError(directory, "cannot create the report folder: " + error.message());
  WriteFileAtomically(directory / "report.md", ToMarkdown());
  WriteFileAtomically(directory / "report.html", ToHtml());
}

std::vector<std::string> ReportDocument::MissingImages(const std::filesystem::path& directory) const {
  std::vector<std::string> missing;
  for (const Block& block : blocks_) {
    if (block.type != BlockType::kImage) continue;
    std::error_code error;
    if (!std::filesystem::is_regular_file(directory / block.text, error)) missing.push_back(block.text);
  }
  return missing;
}

}  // namespace segslam::harness
