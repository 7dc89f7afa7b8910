#include "core/option_assignment.h"

#include <limits>
#include <string>

#include <gtest/gtest.h>

#include "test_util.h"

namespace segslam {
namespace {

using testing::ErrorMessage;

TEST(ParseNumericAssignment, ReadsDecimalAndScientificNotation) {
  EXPECT_DOUBLE_EQ(ParseNumericAssignment("a=0.25", "option").value, 0.25);
  EXPECT_DOUBLE_EQ(ParseNumericAssignment("a=-1.5e-3", "option").value, -1.5e-3);
  EXPECT_DOUBLE_EQ(ParseNumericAssignment("a=+2", "option").value, 2);
  const NumericAssignment parsed = ParseNumericAssignment("moving_share_threshold=0.4", "tracker option");
  EXPECT_EQ(parsed.name, "moving_share_threshold");
  EXPECT_EQ(parsed.text, "0.4");
}

TEST(ParseNumericAssignment, RefusesNonFiniteHexSpacesAndTrailingCharactersNamingOptionAndValue) {
  // std::stod read every one of these (the first three as NaN, inf, 16).
  for (const std::string value : {"nan", "inf", "0x10", "-infinity", "1e400", " 1", "\t1", "1 ", "1x", "", "."}) {
    SCOPED_TRACE("value '" + value + "'");
    const std::string message =
        ErrorMessage([&] { ParseNumericAssignment("moving_share_threshold=" + value, "tracker option"); });
    EXPECT_NE(message.find("tracker option moving_share_threshold: not a number: '" + value + "'"),
              std::string::npos)
        << message;
  }
}

TEST(WholeNumberValue, AcceptsIntRangeAndRefusesFractionsAndOverflow) {
  auto whole = [](const std::string& value) {
    return WholeNumberValue(ParseNumericAssignment("n=" + value, "option"), "option");
  };
  EXPECT_EQ(whole("40"), 40);
  EXPECT_EQ(whole("-2147483648"), std::numeric_limits<int>::min());
  EXPECT_EQ(whole("2147483647"), std::numeric_limits<int>::max());
  for (const std::string value : {"2147483648", "-2147483649", "99999999999999999999", "30.5"}) {
    SCOPED_TRACE("value '" + value + "'");
    EXPECT_NE(ErrorMessage([&] { whole(value); }).find("option n: not a whole number: '" + value + "'"),
              std::string::npos);
  }
  for (const std::string value : {"12abc", "0x7fffffff", "nan"}) {
    SCOPED_TRACE("value '" + value + "'");
    EXPECT_NE(ErrorMessage([&] { whole(value); }).find("option n: not a number: '" + value + "'"), std::string::npos);
  }
}

}  // namespace
}  // namespace segslam
