// Where things live in a DEM file: the step groups and extra-array paths
// both DemFileReader and DemFileWriter name.
#include <fmt/format.h>

#include "dem_file_internal.hpp"
#include <crackvis/dem/dem_file.hpp>

namespace crackvis::dem {

namespace detail {
const char* ownerFolder(ExtraOwner owner) {
  return owner == ExtraOwner::kParticles ? "particles" : "bonds";
}
std::string extraFolder(ExtraOwner owner, bool perStep, int step, StepLayout layout) {
  if (!perStep) {
    return fmt::format("/extra/{}", ownerFolder(owner));
  }
  return layout == StepLayout::kAppendable
             ? fmt::format("/steps/extra/{}", ownerFolder(owner))
             : fmt::format("{}/extra/{}", stepGroupPath(step), ownerFolder(owner));
}
}  // namespace detail

std::string extraPath(const ExtraInfo& extra, int step, StepLayout layout) {
  return fmt::format("{}/{}", detail::extraFolder(extra.owner, extra.perStep, step, layout),
                     extra.name);
}

}  // namespace crackvis::dem
