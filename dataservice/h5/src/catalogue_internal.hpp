// What the parts of the catalogue share (private to dataservice_h5): how
// the service names a stored HDF5 type. The files kept open between calls
// are open_files.hpp.
#pragma once

#include <crackvis/dataservice_protocol/types.hpp>
#include <crackvis/dem/h5.hpp>

namespace crackvis::dataservice {

// The element type of a stored datatype, as the service names it.
DataType classifyType(hid_t type);

}  // namespace crackvis::dataservice
