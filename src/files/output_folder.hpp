// Output folders: created (with their parents) and checked writable before a run writes anything,
// so that a path that is a file, lies under a file, is on a read-only file system or belongs to
// someone else is one clear IoError at the start, never a std::filesystem exception half-way.
#pragma once

#include <string>

namespace city3d::detail {

/// Creates folder `dir` and its parents when missing and checks that a file can be created in it.
/// Throws IoError "<module>: cannot create folder <dir>: <path> is a file, not a folder" (or the
/// system's reason: permission denied, read-only file system, ...), or "<module>: cannot write in
/// folder <dir>: <reason>". `module` names the option in messages ("output", "debug").
void prepare_output_folder(const std::string& dir, const std::string& module);

/// After a run failed: removes folder `dir` (created by that run) when it holds nothing but an empty
/// models/ folder and a resume journal without a finished building (its header line only), so a
/// failed run does not leave a folder that looks like a result. Anything else is left alone.
/// Never throws.
void remove_output_without_results(const std::string& dir) noexcept;

}  // namespace city3d::detail
