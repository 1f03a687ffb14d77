// The rule for names a file or a view gives to its arrays.
#pragma once

#include <string>

#include <crackvis/common/status.hpp>

namespace crackvis::dem {

// Names of extra arrays and step scalars: 1..64 characters of [A-Za-z0-9_.-],
// so they are safe as HDF5 link names and in pipeline descriptions.
Status validateName(const std::string& what, const std::string& name);

}  // namespace crackvis::dem
