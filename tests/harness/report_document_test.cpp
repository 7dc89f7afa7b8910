#include "harness/report_document.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "core/error.h"
#include "tests/core/test_util.h"

namespace segslam::harness {
namespace {

using segslam::testing::TempDirTest;

std::string ReadText(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

size_t Count(const std::string& text, const std::string& what) {
  size_t count = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + what.size())) ++count;
  return count;
}

// '|' not preceded by a backslash: the column separators of a Markdown table line.
size_t UnescapedPipes(const std::string& line) {
  size_t count = 0;
  for (size_t i = 0; i < line.size(); ++i) count += line[i] == '|' && (i == 0 || line[i - 1] != '\\');
  return count;
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::stringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

ReportDocument SampleDocument() {
  ReportDocument document("Run <A> & \"B\"");
  document.AddMetadata("scenario", "scenarios/city_street_grid.yaml");
  document.AddMetadata("seeds", "1, 2, 3");
  document.AddHeading("Trajectories");
  document.AddParagraph("ATE < 5 cm for <script>alert('x')</script>\nsecond line");
  ReportTable table;
  table.caption = "ATE [m] per mode";
  table.header = {"mode", "median", "min", "max"};
  table.rows = {{"plain", "0.120", "0.100", "0.150"},
                {"mask|moveable", "0.050", "0.040", "0.070"},
                {"mutual", "0.030", "", "0.035"}};
  document.AddTable(table);
  document.AddImage("figures/top view.png", "Top view <x-y>");
  return document;
}

TEST(ReportDocumentTest, EscapeHtmlReplacesEverySpecialCharacter) {
  EXPECT_EQ(EscapeHtml("a<b>&\"c\"'d'"), "a&lt;b&gt;&amp;&quot;c&quot;&#39;d&#39;");
  EXPECT_EQ(EscapeHtml("plain text"), "plain text");
}

TEST(ReportDocumentTest, HtmlEscapesTextAndHoldsTheTableAndImage) {
  const std::string html = SampleDocument().ToHtml();
  EXPECT_EQ(html.find("<script>"), std::string::npos);
  EXPECT_NE(html.find("&lt;script&gt;alert(&#39;x&#39;)&lt;/script&gt;"), std::string::npos);
  EXPECT_NE(html.find("<h1>Run &lt;A&gt; &amp; &quot;B&quot;</h1>"), std::string::npos);
  EXPECT_NE(html.find("<title>Run &lt;A&gt; &amp; &quot;B&quot;</title>"), std::string::npos);
  EXPECT_NE(html.find("<dt>seeds</dt><dd>1, 2, 3</dd>"), std::string::npos);
  EXPECT_NE(html.find("<h2>Trajectories</h2>"), std::string::npos);
  // One header row and three body rows of four cells; numeric columns right-aligned.
  EXPECT_EQ(Count(html, "<tr>"), 4u);
  EXPECT_EQ(Count(html, "</th>"), 4u);
  EXPECT_EQ(Count(html, "</td>"), 12u);
  EXPECT_NE(html.find("<th>mode</th><th class=\"num\">median</th>"), std::string::npos);
  EXPECT_NE(html.find("<td>mask|moveable</td>"), std::string::npos);
  EXPECT_NE(html.find("<p class=\"table-caption\">ATE [m] per mode</p>"), std::string::npos);
  // The image by relative, percent-encoded path; its caption escaped.
  EXPECT_NE(html.find("<img src=\"figures/top%20view.png\" alt=\"Top view &lt;x-y&gt;\">"), std::string::npos);
  EXPECT_NE(html.find("<figcaption>Top view &lt;x-y&gt;</figcaption>"), std::string::npos);
  EXPECT_NE(html.find("<style>"), std::string::npos);
}

TEST(ReportDocumentTest, MarkdownTableHasOneColumnPerHeaderCell) {
  const std::string md = SampleDocument().ToMarkdown();
  const std::vector<std::string> lines = Lines(md);
  int table_lines = 0;
  for (const std::string& line : lines) {
    if (line.empty() || line.front() != '|') continue;
    ++table_lines;
    EXPECT_EQ(UnescapedPipes(line), 5u) << line;  // four columns
  }
  EXPECT_EQ(table_lines, 5);  // header, alignment, three rows
  EXPECT_NE(md.find("| mode | median | min | max |"), std::string::npos);
  EXPECT_NE(md.find("| --- | ---: | ---: | ---: |"), std::string::npos);
  EXPECT_NE(md.find("| mask\\|moveable | 0.050 | 0.040 | 0.070 |"), std::string::npos);
  EXPECT_NE(md.find("![Top view \\<x-y\\>](figures/top%20view.png)"), std::string::npos);
  EXPECT_NE(md.find("# Run \\<A\\> & \"B\""), std::string::npos);
  EXPECT_NE(md.find("- **scenario:** scenarios/city\\_street\\_grid.yaml"), std::string::npos);
  // A line break inside a paragraph stays a line break (CommonMark's backslash break).
  EXPECT_NE(md.find("\\</script\\>\\\nsecond line"), std::string::npos);
}

TEST(ReportDocumentTest, ParagraphLinesThatLookLikeMarkdownBlocksAreEscaped) {
  ReportDocument document("t");
  document.AddParagraph("# not a heading\n- not a list\n1. not numbered");
  const std::string md = document.ToMarkdown();
  EXPECT_NE(md.find("\\# not a heading\\\n\\- not a list\\\n1\\. not numbered"), std::string::npos) << md;
}

TEST(ReportDocumentTest, RefusesWhatCannotBeWritten) {
  ReportDocument document("t");
  ReportTable ragged;
  ragged.header = {"a", "b"};
  ragged.rows = {{"1", "2"}, {"3"}};
  try {
    document.AddTable(ragged);
    FAIL() << "a ragged table was accepted";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("row 2 has 1 cells for 2 columns"), std::string::npos) << error.what();
  }
  EXPECT_THROW(document.AddTable(ReportTable{}), Error);
  EXPECT_THROW(document.AddImage("/tmp/a.png", "absolute"), Error);
  EXPECT_THROW(document.AddImage("../a.png", "outside"), Error);
  EXPECT_THROW(document.AddImage("figures/../../a.png", "outside"), Error);
  EXPECT_THROW(document.AddImage("", "empty"), Error);
  EXPECT_THROW(document.AddHeading("h", 1), Error);
  EXPECT_THROW(document.AddHeading("h", 5), Error);
  EXPECT_NO_THROW(document.AddHeading("h", 4));
}

class ReportDocumentFileTest : public TempDirTest {};

TEST_F(ReportDocumentFileTest, WritesBothFilesAndListsMissingImages) {
  ReportDocument document = SampleDocument();
  document.AddImage("figures/present.png", "present");
  const std::filesystem::path out = dir() / "report";
  document.Write(out);
  EXPECT_EQ(ReadText(out / "report.md"), document.ToMarkdown());
  EXPECT_EQ(ReadText(out / "report.html"), document.ToHtml());
  // Only the two documents: no temporary files left behind.
  size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(out)) files += entry.is_regular_file();
  EXPECT_EQ(files, 2u);

  std::filesystem::create_directories(out / "figures");
  std::ofstream(out / "figures" / "present.png") << "png";
  EXPECT_EQ(document.MissingImages(out), std::vector<std::string>{"figures/top view.png"});
}

TEST_F(ReportDocumentFileTest, AnUnwritableFolderIsAnErrorNamingIt) {
  std::ofstream(dir() / "file") << "x";
  try {
    SampleDocument().Write(dir() / "file" / "report");
    FAIL() << "writing under a regular file succeeded";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("file/report"), std::string::npos) << error.what();
  }
}

}  // namespace
}  // namespace segslam::harness
