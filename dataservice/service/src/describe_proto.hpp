// The Describe answer as the protocol carries it: a FileDescription (and a
// DataType) in their crackvis.v1 form. Made in the HDF5 worker processes
// and by the handlers. Private to the service library.
#pragma once

#include "crackvis/v1/data.pb.h"
#include <crackvis/dataservice_protocol/types.hpp>

namespace crackvis::dataservice {

crackvis::v1::DataType toProto(DataType type);
void toProto(const FileDescription& in, crackvis::v1::DescribeResponse& out);

}  // namespace crackvis::dataservice
