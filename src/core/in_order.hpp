// Work over a sequence on several threads whose results are taken in order: where reading (parsing)
// each item is most of the work and what is made of the items must not depend on the threads
// (report.html, the run-level files).
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <optional>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

namespace city3d::detail {

/// For k = 0 .. n - 1: make(k) on up to `threads` threads, `batch` items at a time, then take(k,
/// made) on the calling thread in order of k. When make throws, the exception of the smallest such
/// k is rethrown after the take of every k before it, whichever thread failed first.
template <typename Make, typename Take>
void for_each_in_order(std::size_t n, unsigned threads, std::size_t batch, Make make, Take take) {
  using Made = decltype(make(std::size_t{0}));
  batch = std::max<std::size_t>(batch, 1);
  std::vector<std::optional<Made>> made;
  std::vector<std::exception_ptr> failed;
  for (std::size_t first = 0; first < n; first += batch) {
    const std::size_t count = std::min(batch, n - first);
    made.assign(count, std::nullopt);
    failed.assign(count, nullptr);
    std::atomic<std::size_t> next{0};
    const auto work = [&] {
      for (std::size_t j = next++; j < count; j = next++) {
        try {
          made[j].emplace(make(first + j));
        } catch (...) {
          failed[j] = std::current_exception();
        }
      }
    };
    std::vector<std::thread> helpers;
    try {
      for (unsigned t = 1; t < threads && t < count; ++t) helpers.emplace_back(work);
    } catch (const std::system_error&) {
      // No more threads to be had: the ones started and this one do the batch.
    }
    work();
    for (std::thread& t : helpers) t.join();
    for (std::size_t j = 0; j < count; ++j) {
      if (failed[j]) std::rethrow_exception(failed[j]);
      take(first + j, std::move(*made[j]));
    }
  }
}

}  // namespace city3d::detail
