#pragma once
/// @file data_paths.hpp
/// Where pmg's tools find their data (config/, data/, scripts/), independent of the working
/// directory.
///
/// The data directory is, in this order:
///  1. `$PMG_DATA_DIR` when it is set and not empty;
///  2. the installed data directory next to the running executable, `<exe dir>/../share/pmg`
///     (`cmake --install` puts binaries in `<prefix>/bin` and data in `<prefix>/share/pmg`);
///     executables one level deeper (`build/bin/tests/`) also look in `<exe dir>/../../share/pmg`.
///
/// The build tree has the same layout: `build/share/pmg/config` and `build/share/pmg/data` are
/// symbolic links to the checkout's `config/` and `data/`, so edits in a checkout are seen without
/// re-running CMake, and no source path is compiled into a binary.
///
/// Rules of the tools: defaults (the G1 robot config, the shipped policy, helper scripts) resolve
/// against dataDir() with resolveData(); paths given on the command line stay relative to the
/// working directory; paths named inside a file resolve against that file's folder
/// (resolveRelativeTo()). Setup code only (allocates).

#include <filesystem>
#include <string>

namespace pmg {

/// Folder of the running executable (from /proc/self/exe), e.g. `<prefix>/bin`. Empty if the
/// operating system does not tell.
std::filesystem::path executableDir();

/// pmg's data directory (see the file comment for the search order). The result is absolute and
/// lexically normal. It is returned even when it does not exist (no data installed, executable
/// copied elsewhere): the loader that opens a file below it then names the full path, and
/// `PMG_DATA_DIR` fixes it.
std::filesystem::path dataDir();

/// `dataDir() / relative`, e.g. `resolveData("config/robots/g1/g1.yaml")`. An absolute
/// @p relative is returned unchanged.
std::filesystem::path resolveData(const std::filesystem::path& relative);

/// Resolves @p path as written inside the file @p naming_file: absolute paths are returned
/// unchanged, relative ones are taken against the folder of @p naming_file (which itself may be
/// relative to the working directory). The result is lexically normal; an empty @p path stays
/// empty.
std::filesystem::path resolveRelativeTo(const std::filesystem::path& naming_file, const std::filesystem::path& path);

/// Checks, without creating anything, that a file can be written at @p path: its folder exists and
/// is writable, and @p path is not a folder or a read-only file. Tools call it for every output path
/// before they start work, so a bad path fails at once instead of losing the results.
/// @throws std::runtime_error "<path>: cannot write (<reason>)".
void requireWritableFile(const std::filesystem::path& path);

}  // namespace pmg
