// Speed of KthSmallest on the values the refinement selects a median from: a region's
// measured depths, one slanted surface quantised as 16-bit depth PNGs store it (1/5000 m),
// some 18,000 per region in the walking office.
//
//   core_benchmarks --benchmark_filter=KthSmallest
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "core/statistics.h"

namespace segslam {
namespace {

std::vector<float> SurfaceDepths(std::size_t n) {
  std::mt19937 rng(1812);
  std::uniform_real_distribution<float> along(0.0f, 1.0f);
  std::normal_distribution<float> noise(0.0f, 0.004f);
  std::vector<float> depths(n);
  for (float& z : depths) {
    const float metres = 1.6f + 0.9f * along(rng) + noise(rng);
    z = std::round(metres * 5000.0f) / 5000.0f;
  }
  return depths;
}

// The copy into the scratch buffer is timed too; BM_KthSmallestInputCopy gives its share.
void BM_KthSmallestSurfaceDepths(benchmark::State& state) {
  const std::vector<float> depths = SurfaceDepths(static_cast<std::size_t>(state.range(0)));
  std::vector<float> scratch(depths.size());
  for (auto _ : state) {
    std::copy(depths.begin(), depths.end(), scratch.begin());
    benchmark::DoNotOptimize(KthSmallest(scratch.data(), scratch.size(), scratch.size() / 2));
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_KthSmallestSurfaceDepths)->Arg(18000)->Arg(2000)->Arg(100000);

void BM_KthSmallestInputCopy(benchmark::State& state) {
  const std::vector<float> depths = SurfaceDepths(static_cast<std::size_t>(state.range(0)));
  std::vector<float> scratch(depths.size());
  for (auto _ : state) {
    std::copy(depths.begin(), depths.end(), scratch.begin());
    benchmark::DoNotOptimize(scratch.data());
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_KthSmallestInputCopy)->Arg(18000);

}  // namespace
}  // namespace segslam
