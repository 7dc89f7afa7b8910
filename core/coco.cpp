#include "core/coco.h"

#include <algorithm>

namespace segslam {

const std::vector<CocoCategory>& CocoCategories() {
  // From the COCO 2017 instances_*.json "categories" array.
  static const std::vector<CocoCategory> kCategories = {
      {1, "person", "person"},          {2, "bicycle", "vehicle"},
      {3, "car", "vehicle"},            {4, "motorcycle", "vehicle"},
      {5, "airplane", "vehicle"},       {6, "bus", "vehicle"},
      {7, "train", "vehicle"},          {8, "truck", "vehicle"},
      {9, "boat", "vehicle"},           {10, "traffic light", "outdoor"},
      {11, "fire hydrant", "outdoor"},  {13, "stop sign", "outdoor"},
      {14, "parking meter", "outdoor"}, {15, "bench", "outdoor"},
      {16, "bird", "animal"},           {17, "cat", "animal"},
      {18, "dog", "animal"},            {19, "horse", "animal"},
      {20, "sheep", "animal"},          {21, "cow", "animal"},
      {22, "elephant", "animal"},       {23, "bear", "animal"},
      {24, "zebra", "animal"},          {25, "giraffe", "animal"},
      {27, "backpack", "accessory"},    {28, "umbrella", "accessory"},
      {31, "handbag", "accessory"},     {32, "tie", "accessory"},
      {33, "suitcase", "accessory"},    {34, "frisbee", "sports"},
      {35, "skis", "sports"},           {36, "snowboard", "sports"},
      {37, "sports ball", "sports"},    {38, "kite", "sports"},
      {39, "baseball bat", "sports"},   {40, "baseball glove", "sports"},
      {41, "skateboard", "sports"},     {42, "surfboard", "sports"},
      {43, "tennis racket", "sports"},  {44, "bottle", "kitchen"},
      {46, "wine glass", "kitchen"},    {47, "cup", "kitchen"},
      {48, "fork", "kitchen"},          {49, "knife", "kitchen"},
      {50, "spoon", "kitchen"},         {51, "bowl", "kitchen"},
      {52, "banana", "food"},           {53, "apple", "food"},
      {54, "sandwich", "food"},         {55, "orange", "food"},
      {56, "broccoli", "food"},         {57, "carrot", "food"},
      {58, "hot dog", "food"},          {59, "pizza", "food"},
      {60, "donut", "food"},            {61, "cake", "food"},
      {62, "chair", "furniture"},       {63, "couch", "furniture"},
      {64, "potted plant", "furniture"}, {65, "bed", "furniture"},
      {67, "dining table", "furniture"}, {70, "toilet", "furniture"},
      {72, "tv", "electronic"},         {73, "laptop", "electronic"},
      {74, "mouse", "electronic"},      {75, "remote", "electronic"},
      {76, "keyboard", "electronic"},   {77, "cell phone", "electronic"},
      {78, "microwave", "appliance"},   {79, "oven", "appliance"},
      {80, "toaster", "appliance"},     {81, "sink", "appliance"},
      {82, "refrigerator", "appliance"}, {84, "book", "indoor"},
      {85, "clock", "indoor"},          {86, "vase", "indoor"},
      {87, "scissors", "indoor"},       {88, "teddy bear", "indoor"},
      {89, "hair drier", "indoor"},     {90, "toothbrush", "indoor"},
  };
  return kCategories;
}

const CocoCategory* FindCocoCategory(int id) {
  const auto& categories = CocoCategories();
  const auto it = std::lower_bound(categories.begin(), categories.end(), id,
                                   [](const CocoCategory& c, int v) { return c.id < v; });
  return it != categories.end() && it->id == id ? &*it : nullptr;
}

const CocoCategory* FindCocoCategoryByName(std::string_view name) {
  for (const CocoCategory& category : CocoCategories()) {
    if (category.name == name) return &category;
  }
  return nullptr;
}

const std::vector<int>& MoveableCategoryIds() {
  // Why each group is here: see coco.h.
  static const std::vector<int> kIds = [] {
    std::vector<int> ids = {
        1,                                   // person
        2, 3, 4, 5, 6, 7, 8, 9,              // vehicles
        16, 17, 18, 19, 20, 21, 22, 23, 24, 25,  // animals
        27, 28, 31, 32, 33,                  // accessories
        34, 35, 36, 37, 38, 39, 40, 41, 42, 43,  // sports gear
        44, 46, 47, 48, 49, 50, 51,          // tableware
        52, 53, 54, 55, 56, 57, 58, 59, 60, 61,  // food
        62,                                  // chair
        73, 74, 75, 76, 77,                  // portable electronics
        84, 85, 86, 87, 88, 89, 90,          // small indoor objects
    };
    std::sort(ids.begin(), ids.end());
    return ids;
  }();
  return kIds;
}

bool IsMoveableCategory(int category_id) {
  const auto& ids = MoveableCategoryIds();
  return std::binary_search(ids.begin(), ids.end(), category_id);
}

}  // namespace segslam
