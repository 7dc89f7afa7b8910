#include "core/instances.h"

#include <fstream>

#include <gtest/gtest.h>

#include "core/error.h"
#include "test_util.h"

namespace segslam {
namespace {

using testing::ErrorMessage;
using InstancesTest = testing::TempDirTest;

InstanceTable MakeTable() {
  InstanceTable table;
  table.Add({7, 62, "chair"});
  table.Add({3, 3, ""});  // Name filled in from the id.
  table.Add({12, 67, "dining table"});
  return table;
}

TEST(InstanceTable, AddSortsAndFillsCategory) {
  const InstanceTable table = MakeTable();
  ASSERT_EQ(table.instances().size(), 3u);
  EXPECT_EQ(table.instances()[0].id, 3);
  EXPECT_EQ(table.instances()[1].id, 7);
  EXPECT_EQ(table.instances()[2].id, 12);
  ASSERT_NE(table.Find(3), nullptr);
  EXPECT_EQ(table.Find(3)->category_name, "car");
  EXPECT_TRUE(table.Find(3)->moveable);
  EXPECT_FALSE(table.Find(12)->moveable);
  EXPECT_EQ(table.Find(4), nullptr);
}

TEST(InstanceTable, AddErrors) {
  InstanceTable table = MakeTable();
  EXPECT_NE(ErrorMessage([&] { table.Add({0, 1, ""}); }).find("background"), std::string::npos);
  EXPECT_NE(ErrorMessage([&] { table.Add({3, 1, ""}); }).find("duplicate"), std::string::npos);
  EXPECT_NE(ErrorMessage([&] { table.Add({4, 12, ""}); }).find("unknown COCO"),
            std::string::npos);
  EXPECT_NE(ErrorMessage([&] { table.Add({4, 1, "car"}); }).find("does not match"),
            std::string::npos);
  EXPECT_EQ(table.instances().size(), 3u);
}

TEST_F(InstancesTest, JsonRoundTripThroughFile) {
  const InstanceTable table = MakeTable();
  const auto json = table.ToJson();
  EXPECT_EQ(json["instances"][0]["category"], "car");
  EXPECT_EQ(json["instances"][0]["moveable"], true);
  const auto path = dir() / "instances.json";
  table.Write(path);
  const InstanceTable back = InstanceTable::Read(path);
  ASSERT_EQ(back.instances().size(), table.instances().size());
  for (size_t i = 0; i < table.instances().size(); ++i) {
    EXPECT_EQ(back.instances()[i].id, table.instances()[i].id);
    EXPECT_EQ(back.instances()[i].category_id, table.instances()[i].category_id);
    EXPECT_EQ(back.instances()[i].category_name, table.instances()[i].category_name);
    EXPECT_EQ(back.instances()[i].moveable, table.instances()[i].moveable);
  }
  EXPECT_EQ(back.ToJson(), json);
}

TEST_F(InstancesTest, JsonErrorsNameOrigin) {
  auto from = [](const char* text) {
    return ErrorMessage([&] { InstanceTable::FromJson(nlohmann::json::parse(text), "t.json"); });
  };
  EXPECT_NE(from(R"({"things": []})").find("t.json"), std::string::npos);
  EXPECT_NE(from(R"({"instances": [{"id": 70000, "category_id": 1}]})").find("1..65535"),
            std::string::npos);
  EXPECT_NE(from(R"({"instances": [{"id": 1, "category_id": 12}]})").find("unknown COCO"),
            std::string::npos);
  EXPECT_NE(from(R"({"instances": [{"id": 1, "category_id": "1"}]})").find("integer"),
            std::string::npos);
  EXPECT_NE(from(R"({"instances": [{"id": 1, "category_id": 1, "colour": 2}]})")
                .find("unknown key"),
            std::string::npos);
  EXPECT_NE(from(R"({"instances": [{"id": 1, "category_id": 1, "moveable": false}]})")
                .find("moveable"),
            std::string::npos);
  EXPECT_NE(from(R"({"instances": [{"id": 1, "category_id": 1}, {"id": 1, "category_id": 3}]})")
                .find("instances[1]"),
            std::string::npos);

  const auto path = dir() / "broken.json";
  std::ofstream(path) << "{\"instances\": [";
  const std::string message = ErrorMessage([&] { InstanceTable::Read(path); });
  EXPECT_NE(message.find(path.string()), std::string::npos) << message;
  EXPECT_NE(message.find("malformed JSON"), std::string::npos) << message;
}

TEST(CheckMaskIds, NamesFirstUnknownId) {
  const InstanceTable table = MakeTable();
  cv::Mat mask(4, 5, CV_16UC1, cv::Scalar(0));
  mask.at<std::uint16_t>(1, 1) = 3;
  mask.at<std::uint16_t>(2, 3) = 12;
  EXPECT_NO_THROW(CheckMaskIds(mask, table, "m.png"));
  mask.at<std::uint16_t>(3, 2) = 99;
  mask.at<std::uint16_t>(3, 4) = 98;
  const std::string message = ErrorMessage([&] { CheckMaskIds(mask, table, "m.png"); });
  EXPECT_NE(message.find("m.png"), std::string::npos) << message;
  EXPECT_NE(message.find("99"), std::string::npos) << message;
  EXPECT_EQ(message.find("98"), std::string::npos) << message;
}

}  // namespace
}  // namespace segslam
