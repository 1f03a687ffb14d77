// What the parts of the catalogue share (private to dataservice_h5): how
// the service names a stored HDF5 type. The files kept open between calls
// are open_files.hpp.
#pragma once

#include <string>

#include <crackvis/common/status.hpp>
#include <crackvis/dataservice_h5/catalogue.hpp>
#include <crackvis/dataservice_protocol/types.hpp>
#include <crackvis/dem/h5.hpp>

namespace crackvis::dataservice {

// The element type of a stored datatype, as the service names it.
DataType classifyType(hid_t type);

// Describe's walk of a file already open (`name` for messages); the caller
// holds hdf5Mutex(). Catalogue::describe and the worker's rehearsal share it.
Result<FileDescription> describeOpenFile(hid_t file, const std::string& name,
                                         const DescribeOptions& options);

}  // namespace crackvis::dataservice
