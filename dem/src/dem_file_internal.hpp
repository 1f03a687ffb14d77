// Private to dem/src: the names of the extra-array folders, used by both
// DemFileReader (to list them) and DemFileWriter (to create them).
#pragma once

#include <string>

#include <crackvis/dem/model.hpp>

namespace crackvis::dem::detail {

// "particles" or "bonds": the folder under extra/ that holds an owner's arrays.
const char* ownerFolder(ExtraOwner owner);
// The extra/{particles,bonds} group of the root (constant arrays) or of a step.
std::string extraFolder(ExtraOwner owner, bool perStep, int step);

}  // namespace crackvis::dem::detail
