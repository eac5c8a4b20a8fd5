// The progress line a batch run writes on stderr while it reconstructs (--progress).
#pragma once

#include <chrono>
#include <cstddef>
#include <mutex>

namespace city3d::detail {

/// The progress line on stderr. Its rate counts the buildings this run reconstructed over the time
/// it spent reconstructing (reading tiles and resumed buildings left out: they made the first
/// estimate of the Delft block 86 s for a 5.8 s run), and it says nothing of the time left until
/// a few buildings (kProgressSample, or 2% of them) are done. Thread-safe; silent when not `on`.
class Progress {
 public:
  static constexpr std::size_t kProgressSample = 5;
  Progress(bool on, std::size_t total, std::size_t resumed) : on_(on), total_(total), done_(resumed) {}
  /// While tiles are read for the next buildings.
  void reading(std::size_t tiles, std::size_t buildings);
  void start_reconstructing();
  void stop_reconstructing();
  /// One more building finished.
  void building_done();
  /// Ends the line (the summary follows on its own).
  void finish();

 private:
  using Clock = std::chrono::steady_clock;
  bool on_;
  std::size_t total_, done_, built_ = 0;
  double spent_ = 0.0;
  Clock::time_point since_ = Clock::now();
  std::mutex mutex_;
};

}  // namespace city3d::detail
