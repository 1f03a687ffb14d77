// The element types crackvis-dem's datasets use, without HDF5: the layout
// (layout.hpp) and the data service's wire types name them, so that no
// network header compiles <hdf5.h>; dem/h5.hpp maps them to HDF5's types.
#pragma once

namespace crackvis::dem {

enum class ElementType { kInt32, kInt64, kUInt8, kFloat32, kFloat64, kOther };
// "int32", ... in messages; "other" for kOther.
const char* elementTypeName(ElementType type);

}  // namespace crackvis::dem
