// The progress line of a batch run (progress.hpp).
#include "batch/progress.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace city3d::detail {

void Progress::reading(std::size_t tiles, std::size_t buildings) {
  if (!on_) return;
  std::lock_guard<std::mutex> lock(mutex_);
  std::fprintf(stderr, "\rbuildings %zu/%zu  reading %zu tile%s for the next %zu...%20s", done_, total_,
               tiles, tiles == 1 ? "" : "s", buildings, "");
  std::fflush(stderr);
}

void Progress::start_reconstructing() {
  std::lock_guard<std::mutex> lock(mutex_);
  since_ = Clock::now();
}

void Progress::stop_reconstructing() {
  std::lock_guard<std::mutex> lock(mutex_);
  spent_ += std::chrono::duration<double>(Clock::now() - since_).count();
}

void Progress::building_done() {
  std::lock_guard<std::mutex> lock(mutex_);
  ++done_;
  ++built_;
  if (!on_) return;
  const double spent = spent_ + std::chrono::duration<double>(Clock::now() - since_).count();
  const double rate = spent > 0 ? built_ / spent : 0.0;
  if (built_ < std::max<std::size_t>(kProgressSample, total_ / 50) || rate <= 0)
    std::fprintf(stderr, "\rbuildings %zu/%zu  estimating the time left...%20s", done_, total_, "");
  else
    std::fprintf(stderr, "\rbuildings %zu/%zu  %.1f/s  about %.0f s left%20s", done_, total_, rate,
                 std::ceil((total_ - done_) / rate), "");
  std::fflush(stderr);
}

void Progress::finish() {
  if (!on_) return;
  std::fprintf(stderr, "\rbuildings %zu/%zu%60s\n", done_, total_, "");
  std::fflush(stderr);
}

}  // namespace city3d::detail
