#include "core/coco.h"

#include <algorithm>
#include <set>

#include <gtest/gtest.h>

namespace segslam {
namespace {

TEST(Coco, EightyCategoriesWithUniqueSortedIds) {
  const auto& categories = CocoCategories();
  ASSERT_EQ(categories.size(), 80u);
  std::set<int> ids;
  std::set<std::string_view> names;
  for (size_t i = 0; i < categories.size(); ++i) {
    ids.insert(categories[i].id);
    names.insert(categories[i].name);
    if (i > 0) {
      EXPECT_LT(categories[i - 1].id, categories[i].id);
    }
    EXPECT_GE(categories[i].id, 1);
    EXPECT_LE(categories[i].id, 90);
    EXPECT_FALSE(categories[i].supercategory.empty());
  }
  EXPECT_EQ(ids.size(), 80u);
  EXPECT_EQ(names.size(), 80u);
  // The 10 ids COCO skips.
  for (int missing : {12, 26, 29, 30, 45, 66, 68, 69, 71, 83}) {
    EXPECT_EQ(FindCocoCategory(missing), nullptr) << missing;
  }
}

TEST(Coco, KnownIds) {
  const std::pair<int, std::string_view> known[] = {
      {1, "person"},       {3, "car"},   {10, "traffic light"}, {13, "stop sign"},
      {15, "bench"},       {44, "bottle"}, {62, "chair"},      {67, "dining table"},
      {72, "tv"},          {82, "refrigerator"}, {90, "toothbrush"}};
  for (const auto& [id, name] : known) {
    const CocoCategory* category = FindCocoCategory(id);
    ASSERT_NE(category, nullptr) << id;
    EXPECT_EQ(category->name, name);
    EXPECT_EQ(FindCocoCategoryByName(name), category);
  }
  EXPECT_EQ(FindCocoCategory(1)->supercategory, "person");
  EXPECT_EQ(FindCocoCategory(3)->supercategory, "vehicle");
  EXPECT_EQ(FindCocoCategory(0), nullptr);
  EXPECT_EQ(FindCocoCategory(91), nullptr);
  EXPECT_EQ(FindCocoCategoryByName("Person"), nullptr);
}

TEST(Coco, MoveableShortlist) {
  for (const char* name : {"person", "car", "bicycle", "dog", "chair", "cup", "laptop",
                           "backpack", "suitcase", "book", "teddy bear"}) {
    EXPECT_TRUE(IsMoveableCategory(FindCocoCategoryByName(name)->id)) << name;
  }
  for (const char* name : {"traffic light", "fire hydrant", "stop sign", "bench",
                           "dining table", "tv", "potted plant", "bed", "couch",
                           "refrigerator", "sink", "toilet"}) {
    EXPECT_FALSE(IsMoveableCategory(FindCocoCategoryByName(name)->id)) << name;
  }
  EXPECT_FALSE(IsMoveableCategory(0));
  EXPECT_FALSE(IsMoveableCategory(12));
  const auto& ids = MoveableCategoryIds();
  EXPECT_TRUE(std::is_sorted(ids.begin(), ids.end()));
  for (int id : ids) EXPECT_NE(FindCocoCategory(id), nullptr) << id;
}

}  // namespace
}  // namespace segslam
