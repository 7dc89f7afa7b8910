// `segslam masks images | import | export` on a generated sequence (fixture sim_datasets):
// the ground-truth masks, sent through the way a network's output comes (an image list, a
// COCO results file with compressed RLE and integer image ids), come back as the same
// masks, which seg-eval then scores as perfect; the simulated segmenter's output exported
// and imported keeps every pixel; export and import are inverse; refused input and an
// existing folder leave nothing behind.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include "core/coco_rle.h"
#include "tests/harness/cli_runner.h"

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using segslam::testing::CommandOutput;
using segslam::testing::ReadText;

const fs::path kDataDir = SEGSLAM_TEST_DATA_DIR;

class MasksCliTest : public segslam::testing::CliScratchTest {
 protected:
  MasksCliTest() : CliScratchTest("segslam_masks_") {}

  const fs::path sequence_ = kDataDir / "office_clean" / "pass1";
};

// The ground truth of `sequence` as a network's results for the images of `image_list`.
json GroundTruthAsResults(const fs::path& sequence, const json& image_list) {
  const json instances = json::parse(ReadText(sequence / "instances.json"));
  std::map<int, int> category_of;
  for (const json& instance : instances.at("instances")) {
    category_of[instance.at("id").get<int>()] = instance.at("category_id").get<int>();
  }
  json results = json::array();
  for (const json& image : image_list.at("images")) {
    const fs::path mask_file = sequence / "masks" / fs::path(image.at("file_name").get<std::string>()).filename();
    const cv::Mat ids = cv::imread(mask_file.string(), cv::IMREAD_UNCHANGED);
    std::map<int, bool> seen;
    for (auto it = ids.begin<std::uint16_t>(); it != ids.end<std::uint16_t>(); ++it) {
      if (*it != 0) seen[*it] = true;
    }
    for (const auto& [id, unused] : seen) {
      const cv::Mat mask = ids == id;
      results.push_back({{"image_id", image.at("id")},
                         {"category_id", category_of.at(id)},
                         {"segmentation",
                          {{"size", {ids.rows, ids.cols}},
                           {"counts", segslam::EncodeCocoRleString(segslam::CocoRleCounts(mask))}}},
                         {"score", 0.5 + 0.4 * (id % 2)}});
    }
  }
  return results;
}

TEST_F(MasksCliTest, GroundTruthThroughAResultsFileComesBackAsItWas) {
  ASSERT_TRUE(fs::is_directory(sequence_)) << sequence_;
  const fs::path images_file = dir_ / "images.json";
  const CommandOutput listed = Run("masks images " + sequence_.string() + " --out " + images_file.string());
  ASSERT_EQ(listed.exit_code, 0) << listed.stderr_text;
  const json images = json::parse(ReadText(images_file));
  ASSERT_EQ(images.at("images").size(), 40u);
  EXPECT_EQ(images.at("images")[0].at("id"), 1);
  EXPECT_EQ(images.at("images")[0].at("file_name").get<std::string>().rfind("rgb/", 0), 0u);
  EXPECT_EQ(images.at("categories").size(), 80u);

  const fs::path results_file = dir_ / "results.json";
  std::ofstream(results_file) << GroundTruthAsResults(sequence_, images).dump();
  const fs::path masks = dir_ / "masks";
  const CommandOutput imported = Run("masks import " + sequence_.string() + " " + results_file.string() +
                                     " --images " + images_file.string() + " --out " + masks.string() +
                                     " --min-score 0 -q");
  ASSERT_EQ(imported.exit_code, 0) << imported.stderr_text;
  EXPECT_NE(imported.stdout_text.find("frames with a kept detection"), std::string::npos) << imported.stdout_text;

  // Each written mask partitions the image exactly as the ground truth does.
  for (const json& image : images.at("images")) {
    const std::string name = fs::path(image.at("file_name").get<std::string>()).filename().string();
    const cv::Mat truth = cv::imread((sequence_ / "masks" / name).string(), cv::IMREAD_UNCHANGED);
    const cv::Mat written = cv::imread((masks / name).string(), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(written.type(), CV_16UC1) << name;
    ASSERT_EQ(written.size(), truth.size()) << name;
    std::map<int, int> truth_of_written, written_of_truth;
    bool same_partition = true;
    for (int y = 0; y < truth.rows; ++y) {
      for (int x = 0; x < truth.cols; ++x) {
        const int t = truth.at<std::uint16_t>(y, x), w = written.at<std::uint16_t>(y, x);
        same_partition = same_partition && truth_of_written.emplace(w, t).first->second == t &&
                         written_of_truth.emplace(t, w).first->second == w;
      }
    }
    EXPECT_TRUE(same_partition) << name;
    EXPECT_EQ(truth_of_written.count(0) ? truth_of_written.at(0) : 0, 0) << name;
  }

  // As a segmenter's output they are perfect: seg-eval reads them and scores raw mAP 1.
  const CommandOutput scored =
      Run("seg-eval " + sequence_.string() + " --masks " + masks.string() + " --out " + (dir_ / "eval").string());
  ASSERT_EQ(scored.exit_code, 0) << scored.stderr_text;
  const json eval = json::parse(ReadText(dir_ / "eval" / "seg_eval.json"));
  EXPECT_DOUBLE_EQ(eval.at("sequences")[0].at("raw").at("mAP").get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(eval.at("sequences")[0].at("raw").at("mIoU").get<double>(), 1.0);

  // The folder exists now: without --force it is kept as it is.
  const CommandOutput again = Run("masks import " + sequence_.string() + " " + results_file.string() + " --images " +
                                  images_file.string() + " --out " + masks.string() + " -q");
  EXPECT_EQ(again.exit_code, 1);
  EXPECT_NE(again.stderr_text.find("already exists (use --force to replace it)"), std::string::npos)
      << again.stderr_text;
  const CommandOutput forced = Run("masks import " + sequence_.string() + " " + results_file.string() +
                                   " --images " + images_file.string() + " --out " + masks.string() +
                                   " --min-score 0.7 --force -q");
  ASSERT_EQ(forced.exit_code, 0) << forced.stderr_text;
  EXPECT_NE(forced.stdout_text.find("scoring below 0.7"), std::string::npos) << forced.stdout_text;
}

// The simulated segmenter's output as COCO results, imported, scores the same pixels as
// the segmenter read directly: the same per-class pixel counts and mIoU. Only detections
// that higher-scoring ones cover entirely are gone (the folder holds one id per pixel), so
// mAP may differ. Exporting the imported folder and importing it again changes nothing.
TEST_F(MasksCliTest, ExportAndImportAreInverse) {
  ASSERT_TRUE(fs::is_directory(sequence_)) << sequence_;
  const std::string images = (dir_ / "images.json").string();
  ASSERT_EQ(Run("masks images " + sequence_.string() + " --out " + images).exit_code, 0);
  const std::string simulated = (dir_ / "simulated.json").string();
  const CommandOutput exported =
      Run("masks export " + sequence_.string() + " --segmenter fcis-like --seed 3 --out " + simulated + " -q");
  ASSERT_EQ(exported.exit_code, 0) << exported.stderr_text;
  const fs::path folder = dir_ / "imported";
  const CommandOutput imported = Run("masks import " + sequence_.string() + " " + simulated + " --images " + images +
                                     " --min-score 0 --out " + folder.string() + " -q");
  ASSERT_EQ(imported.exit_code, 0) << imported.stderr_text;

  ASSERT_EQ(Run("seg-eval " + sequence_.string() + " --masks " + folder.string() + " --out " +
                (dir_ / "via_coco").string())
                .exit_code,
            0);
  ASSERT_EQ(Run("seg-eval " + sequence_.string() + " --segmenter fcis-like --seed 3 --out " +
                (dir_ / "direct").string())
                .exit_code,
            0);
  const json via_coco = json::parse(ReadText(dir_ / "via_coco" / "seg_eval.json")).at("sequences")[0].at("raw");
  const json direct = json::parse(ReadText(dir_ / "direct" / "seg_eval.json")).at("sequences")[0].at("raw");
  EXPECT_EQ(via_coco.at("mIoU"), direct.at("mIoU"));
  ASSERT_EQ(via_coco.at("categories").size(), direct.at("categories").size());
  for (size_t c = 0; c < direct.at("categories").size(); ++c) {
    for (const char* count : {"tp_pixels", "fp_pixels", "fn_pixels"}) {
      EXPECT_EQ(via_coco.at("categories")[c].at(count), direct.at("categories")[c].at(count))
          << direct.at("categories")[c].at("category") << " " << count;
    }
  }
  EXPECT_LE(via_coco.at("detections").get<int>(), direct.at("detections").get<int>());
  EXPECT_GT(via_coco.at("detections").get<int>(), 0);

  const std::string again = (dir_ / "again.json").string();
  ASSERT_EQ(Run("masks export " + sequence_.string() + " --masks " + folder.string() + " --out " + again + " -q")
                .exit_code,
            0);
  const fs::path folder_again = dir_ / "imported_again";
  ASSERT_EQ(Run("masks import " + sequence_.string() + " " + again + " --images " + images +
                " --min-score 0 --out " + folder_again.string() + " -q")
                .exit_code,
            0);
  int files = 0;
  for (const auto& entry : fs::directory_iterator(folder)) {
    EXPECT_EQ(ReadText(entry.path()), ReadText(folder_again / entry.path().filename())) << entry.path().filename();
    ++files;
  }
  EXPECT_EQ(files, 81);  // a PNG and a table per frame, and the folder's segslam_sequence.json
  EXPECT_TRUE(fs::exists(folder / "segslam_sequence.json"));

  const CommandOutput neither = Run("masks export " + sequence_.string() + " --out " + again);
  EXPECT_EQ(neither.exit_code, 1);
  EXPECT_NE(neither.stderr_text.find("either --masks DIR or --segmenter PRESET"), std::string::npos);
}

// import --force replaces only a folder of masks that segslam wrote (its record
// segslam_sequence.json and the masks): it deleted a folder of other files whatever it held.
TEST_F(MasksCliTest, ForceReplacesOnlyAFolderOfMasksThatSegslamWrote) {
  ASSERT_TRUE(fs::is_directory(sequence_)) << sequence_;
  const fs::path image_list = dir_ / "images.json", results_file = dir_ / "results.json";
  ASSERT_EQ(Run("masks images " + sequence_.string() + " --out " + image_list.string()).exit_code, 0);
  std::ofstream(results_file) << R"([{"image_id": 1, "category_id": 1, "score": 0.9,
                                      "segmentation": {"size": [480, 640], "counts": [1000, 500, 305700]}}])";
  const std::string import = "masks import " + sequence_.string() + " " + results_file.string() + " --images " +
                             image_list.string() + " -q --force --out ";

  const fs::path notes = dir_ / "notes";
  fs::create_directories(notes / "sub");
  std::ofstream(notes / "sub" / "t.tex") << "precious";
  std::ofstream(notes / "0.000000.png") << "a picture of mine";
  const CommandOutput refused = Run(import + notes.string());
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.stderr_text.find(notes.string() + ": holds what segslam did not write"), std::string::npos)
      << refused.stderr_text;
  EXPECT_EQ(ReadText(notes / "sub" / "t.tex"), "precious");
  EXPECT_EQ(ReadText(notes / "0.000000.png"), "a picture of mine");

  // What import wrote, it replaces.
  const fs::path masks = dir_ / "masks";
  ASSERT_EQ(Run(import + masks.string()).exit_code, 0);
  const CommandOutput again = Run(import + masks.string());
  EXPECT_EQ(again.exit_code, 0) << again.stderr_text;
  EXPECT_TRUE(fs::exists(masks / "segslam_sequence.json"));
  for (const auto& entry : fs::directory_iterator(dir_)) {
    EXPECT_EQ(entry.path().filename().string().find(".partial"), std::string::npos) << entry.path();
  }
}

TEST_F(MasksCliTest, RefusedInputLeavesNoFolder) {
  ASSERT_TRUE(fs::is_directory(sequence_)) << sequence_;
  // Integer image ids without the image list they refer to.
  const fs::path results_file = dir_ / "results.json";
  std::ofstream(results_file) << R"([{"image_id": 1, "category_id": 1, "score": 0.9,
                                      "segmentation": {"size": [480, 640], "counts": "0"}}])";
  const fs::path masks = dir_ / "masks";
  const CommandOutput refused =
      Run("masks import " + sequence_.string() + " " + results_file.string() + " --out " + masks.string());
  EXPECT_EQ(refused.exit_code, 1);
  EXPECT_NE(refused.stderr_text.find(results_file.string() + ": detection 0 (image_id 1): an integer image_id needs"),
            std::string::npos)
      << refused.stderr_text;
  EXPECT_FALSE(fs::exists(masks));

  // A mask that does not cover the image is found while writing the last frame: the
  // folder with the 39 frames before it goes.
  std::ofstream(results_file) << R"([{"image_id": 40, "category_id": 1, "score": 0.9,
                                      "segmentation": {"size": [480, 640], "counts": "0"}}])";
  const CommandOutput images = Run("masks images " + sequence_.string() + " --out " + (dir_ / "images.json").string());
  ASSERT_EQ(images.exit_code, 0) << images.stderr_text;
  const CommandOutput short_counts = Run("masks import " + sequence_.string() + " " + results_file.string() +
                                         " --images " + (dir_ / "images.json").string() + " --out " + masks.string());
  EXPECT_EQ(short_counts.exit_code, 1);
  EXPECT_NE(short_counts.stderr_text.find("RLE counts cover 0 pixels, a 640x480 mask has 307200"), std::string::npos)
      << short_counts.stderr_text;
  EXPECT_FALSE(fs::exists(masks));

  // --force never replaces the sequence's own masks.
  const CommandOutput onto_truth = Run("masks import " + sequence_.string() + " " + results_file.string() +
                                       " --images " + (dir_ / "images.json").string() + " --out " +
                                       (sequence_ / "masks").string() + " --force");
  EXPECT_EQ(onto_truth.exit_code, 1);
  EXPECT_NE(onto_truth.stderr_text.find("is the sequence's own masks/; write the masks elsewhere"), std::string::npos)
      << onto_truth.stderr_text;
  EXPECT_TRUE(fs::exists(sequence_ / "masks" / "0.000000.png"));
  for (const auto& entry : fs::directory_iterator(dir_)) {
    EXPECT_EQ(entry.path().filename().string().find(".masks.partial"), std::string::npos) << entry.path();
  }
}

}  // namespace
