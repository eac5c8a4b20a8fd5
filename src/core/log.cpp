// The logger behind log.hpp: one mutex, one line per call, stderr only.
#include "city3d/log.hpp"

#include <atomic>
#include <cstdio>
#include <mutex>

namespace city3d {
namespace {
std::atomic<int> g_level{static_cast<int>(LogLevel::warning)};
std::mutex g_mutex;
}  // namespace

void set_log_level(LogLevel level) { g_level = static_cast<int>(level); }
LogLevel log_level() { return static_cast<LogLevel>(g_level.load()); }

void log(LogLevel level, const std::string& message) {
  if (static_cast<int>(level) > g_level.load()) return;
  std::lock_guard<std::mutex> lock(g_mutex);
  const char* prefix = level == LogLevel::warning ? "warning: " : "";
  std::fprintf(stderr, "%s%s\n", prefix, message.c_str());
}

}  // namespace city3d
