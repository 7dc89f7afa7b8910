#include "core/strings.h"

#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace segslam {
namespace {

TEST(Join, PutsTheSeparatorBetweenEachTwoPartsEmptyOnesIncluded) {
  EXPECT_EQ(Join({}, ", "), "");
  EXPECT_EQ(Join({"a"}, ", "), "a");
  EXPECT_EQ(Join({"a", "b", "c"}, ", "), "a, b, c");
  EXPECT_EQ(Join({"", "a", ""}, "|"), "|a|");
}

TEST(Split, KeepsEmptyPiecesAndUndoesJoin) {
  EXPECT_EQ(Split("", ','), std::vector<std::string>{""});
  EXPECT_EQ(Split("a", ','), std::vector<std::string>{"a"});
  EXPECT_EQ(Split("a,,b", ','), (std::vector<std::string>{"a", "", "b"}));
  EXPECT_EQ(Split(",a,", ','), (std::vector<std::string>{"", "a", ""}));
  for (const std::string text : {"", ",", "pass1.mutual.ate_rmse_m", "..x."}) {
    EXPECT_EQ(Join(Split(text, '.'), "."), text) << text;
  }
}

TEST(Contains, FindsOnlyWholeEntries) {
  const std::vector<std::string> modes = {"plain", "mutual"};
  EXPECT_TRUE(Contains(modes, "mutual"));
  EXPECT_FALSE(Contains(modes, "mut"));
  EXPECT_FALSE(Contains({}, ""));
}

}  // namespace
}  // namespace segslam
