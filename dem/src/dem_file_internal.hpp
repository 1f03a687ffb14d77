// Private to dem/src: the names of the extra-array folders, used by both
// DemFileReader (to list them) and DemFileWriter (to create them).
#pragma once

#include <string>

#include <crackvis/dem/model.hpp>
#include <crackvis/dem_layout/layout.hpp>

namespace crackvis::dem::detail {

// "particles" or "bonds": the folder under extra/ that holds an owner's arrays.
const char* ownerFolder(ExtraOwner owner);
// The extra/{particles,bonds} group of the root (constant arrays), of a step
// group, or of /steps in an appendable file.
std::string extraFolder(ExtraOwner owner, bool perStep, int step,
                        StepLayout layout = StepLayout::kGroups);

}  // namespace crackvis::dem::detail
