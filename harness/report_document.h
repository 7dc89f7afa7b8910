// A report as a list of blocks (metadata, headings, paragraphs, tables, images) written
// twice: report.md (GitHub Markdown) and report.html (one self-contained file with inline
// CSS; images referenced by relative path, so the report folder can be moved whole).
//
// Text is plain: the builder escapes it for each format, so a table cell "<5 m" or
// "a|b" shows as written. Both files are written atomically.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace segslam::harness {

struct ReportTable {
  std::string caption;                          // shown above the table; may be empty
  std::vector<std::string> header;              // column names; at least one
  std::vector<std::vector<std::string>> rows;   // each with header.size() cells
};

class ReportDocument {
 public:
  explicit ReportDocument(std::string title);

  // "key: value" lines under the title: scenario, seeds, code version, machine, ...
  void AddMetadata(std::string key, std::string value);
  // level 2..4 (the title is level 1). Throws segslam::Error for another level.
  void AddHeading(std::string text, int level = 2);
  // A paragraph; line breaks in `text` are kept.
  void AddParagraph(std::string text);
  // Throws segslam::Error if the header is empty or a row has another number of cells.
  // Columns whose every non-empty cell is a number are right-aligned.
  void AddTable(ReportTable table);
  // `relative_path` from the report's folder, with '/' separators (e.g.
  // "figures/top_view.png"). Throws segslam::Error for an empty or absolute path or one
  // that leaves the folder ("..").
  void AddImage(std::string relative_path, std::string caption);

  std::string ToMarkdown() const;
  std::string ToHtml() const;

  // Writes `directory`/report.md and `directory`/report.html atomically, creating the
  // directory if needed. Throws segslam::Error naming the file on failure.
  void Write(const std::filesystem::path& directory) const;

  // The images' relative paths that do not name a regular file under `directory`.
  std::vector<std::string> MissingImages(const std::filesystem::path& directory) const;

  const std::string& title() const { return title_; }

 private:
  enum class BlockType { kHeading, kParagraph, kTable, kImage };
  struct Block {
    BlockType type = BlockType::kParagraph;
    int level = 2;       // headings
    std::string text;    // heading or paragraph text, image path
    std::string caption; // image caption
    ReportTable table;
  };

  std::string title_;
  std::vector<std::pair<std::string, std::string>> metadata_;
  std::vector<Block> blocks_;
};

// Text with &, <, >, " and ' replaced by HTML entities.
std::string EscapeHtml(const std::string& text);

}  // namespace segslam::harness
