#include "harness/progress_bar.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <unistd.h>

namespace segslam::harness {

ProgressBar::ProgressBar(std::string label, std::string unit)
    : label_(std::move(label)),
      unit_(std::move(unit)),
      rate_unit_(unit_ == "frames" ? "fps" : unit_ + "/s"),
      interactive_(::isatty(STDERR_FILENO) != 0) {}

void ProgressBar::Update(int done, int total, double rate_per_s, const std::string& detail) {
  const double fraction = total > 0 ? std::clamp(static_cast<double>(done) / total, 0.0, 1.0) : 1.0;
  const double eta_s = rate_per_s > 0 ? (total - done) / rate_per_s : 0.0;
  if (interactive_) {
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(fraction * kWidth);
    std::fprintf(stderr, "\r%s [%s%s] %d/%d %s %s %.1f %s, %.0f s left   ", label_.c_str(),
                 std::string(filled, '#').c_str(), std::string(kWidth - filled, '.').c_str(), done,
                 total, unit_.c_str(), detail.c_str(), rate_per_s, rate_unit_.c_str(), eta_s);
    std::fflush(stderr);
    line_open_ = true;
    return;
  }
  const int decile = static_cast<int>(fraction * 10);
  if (decile != last_logged_decile_) {
    last_logged_decile_ = decile;
    std::fprintf(stderr, "%s %3.0f%% %d/%d %s %s %.1f %s, %.0f s left\n", label_.c_str(),
                 100 * fraction, done, total, unit_.c_str(), detail.c_str(), rate_per_s, rate_unit_.c_str(),
                 eta_s);
  }
}

void ProgressBar::Finish() {
  if (line_open_) std::fputc('\n', stderr);
  line_open_ = false;
}

}  // namespace segslam::harness
