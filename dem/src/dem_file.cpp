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
std::string extraFolder(ExtraOwner owner, bool perStep, int step) {
  return perStep ? fmt::format("{}/extra/{}", stepGroupPath(step), ownerFolder(owner))
                 : fmt::format("/extra/{}", ownerFolder(owner));
}
}  // namespace detail

std::string extraPath(const ExtraInfo& extra, int step) {
  return fmt::format("{}/{}", detail::extraFolder(extra.owner, extra.perStep, step), extra.name);
}

}  // namespace crackvis::dem
