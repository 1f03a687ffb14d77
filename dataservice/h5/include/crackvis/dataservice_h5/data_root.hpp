// crackvis-data's data root. The path rules (DataRoot: normalized paths,
// symlinks that must stay inside the root) are shared with crackvis-render
// and live in crackvis/common/data_root.hpp; they are named here as the
// data service has always named them.
#pragma once

#include <filesystem>

#include <crackvis/common/data_root.hpp>

namespace crackvis::dataservice {

using crackvis::DataRoot;
using crackvis::ResolvedPath;

// Whether the file carries the HDF5 signature where HDF5 looks for it (offset
// 0, 512, 1024, 2048, ...). Reads a few bytes; no HDF5 call.
bool hasHdf5Signature(const std::filesystem::path& file);

}  // namespace crackvis::dataservice
