// The 80 COCO object categories with their official ids (1..90 with gaps, as in the
// COCO 2017 annotation files) and supercategories, plus segslam's "moveable" shortlist.
//
// Moveable categories are things that move on their own or are routinely carried or
// relocated between visits. Features on them must never enter the long-term map, even
// when the object is static while mapped: a map reused next day would otherwise hold a
// car that has since driven off or a chair that was pushed elsewhere (DESIGN.md, core
// step 5, and the `mask-moveable` baseline). The list, by COCO id:
//   people and animals: person 1, bird 16, cat 17, dog 18, horse 19, sheep 20, cow 21,
//     elephant 22, bear 23, zebra 24, giraffe 25 (all move on their own);
//   vehicles: bicycle 2, car 3, motorcycle 4, airplane 5, bus 6, train 7, truck 8,
//     boat 9 (they drive/sail away);
//   carried items: backpack 27, umbrella 28, handbag 31, tie 32, suitcase 33,
//     frisbee 34, skis 35, snowboard 36, sports ball 37, kite 38, baseball bat 39,
//     baseball glove 40, skateboard 41, surfboard 42, tennis racket 43,
//     bottle 44, wine glass 46, cup 47, fork 48, knife 49, spoon 50, bowl 51,
//     all food 52-61 (banana .. cake), laptop 73, mouse 74, remote 75, keyboard 76,
//     cell phone 77, book 84, clock 85 (wall clocks are fixed, but table clocks are
//     not and COCO does not tell them apart), vase 86, scissors 87, teddy bear 88,
//     hair drier 89, toothbrush 90;
//   furniture that is pushed around: chair 62.
// Not moveable (fixtures or heavy furniture that stays put between visits): traffic
// light, fire hydrant, stop sign, parking meter, bench, couch, potted plant, bed,
// dining table, toilet, tv, microwave, oven, toaster, sink, refrigerator.
#pragma once

#include <string_view>
#include <vector>

namespace segslam {

struct CocoCategory {
  int id;                          // Official COCO id, 1..90.
  std::string_view name;           // E.g. "traffic light" (COCO spelling, lower case).
  std::string_view supercategory;  // E.g. "outdoor".
};

// All 80 categories sorted by id. The views point at static storage.
const std::vector<CocoCategory>& CocoCategories();

// nullptr if `id` is not a COCO category id.
const CocoCategory* FindCocoCategory(int id);

// nullptr if `name` is not a COCO category name (exact, case-sensitive match).
const CocoCategory* FindCocoCategoryByName(std::string_view name);

// True for the moveable shortlist above; false for other and for unknown ids.
bool IsMoveableCategory(int category_id);

// The moveable shortlist's ids, sorted ascending.
const std::vector<int>& MoveableCategoryIds();

}  // namespace segslam
