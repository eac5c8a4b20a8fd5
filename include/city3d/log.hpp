// The one logger of the library: messages go to stderr, prefixed by nothing but what the caller says
// ("las: ..."). The library never writes to std::cout.
#pragma once

#include <string>

namespace city3d {

enum class LogLevel { quiet = 0, warning = 1, info = 2, debug = 3 };

/// Sets the global verbosity (default: warning). Thread-safe.
void set_log_level(LogLevel level);
LogLevel log_level();

/// Writes one line to stderr when `level` is enabled. Thread-safe: lines never interleave.
void log(LogLevel level, const std::string& message);
inline void log_warning(const std::string& m) { log(LogLevel::warning, m); }
inline void log_info(const std::string& m) { log(LogLevel::info, m); }
inline void log_debug(const std::string& m) { log(LogLevel::debug, m); }

}  // namespace city3d
