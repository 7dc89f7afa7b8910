// A one-line progress bar on stderr: frames done, frames per second, time left.
// On a terminal it redraws in place; in a log (CI) it prints a line every 10%.
#pragma once

#include <string>

namespace segslam::harness {

class ProgressBar {
 public:
  // `unit` names the items counted ("frames": the rate reads "fps"; else "<unit>/s").
  explicit ProgressBar(std::string label, std::string unit = "frames");
  // `done` of `total` items, at `rate_per_s`; `detail` follows the count.
  void Update(int done, int total, double rate_per_s, const std::string& detail = "");
  // Ends the line (on a terminal) so later output starts on a new line.
  void Finish();

 private:
  std::string label_;
  std::string unit_;
  std::string rate_unit_;
  bool interactive_;
  int last_logged_decile_ = -1;
  bool line_open_ = false;
};

}  // namespace segslam::harness
