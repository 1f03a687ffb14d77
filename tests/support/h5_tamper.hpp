// Deliberate damage to valid crackvis-dem files, one defect at a time, for
// the validation tests. Each helper opens the file read-write through the
// HDF5 C API, changes one thing and closes it; failures throw, since they
// are bugs in the test itself.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <crackvis/dem/h5.hpp>

namespace crackvis::testing {

void setStringAttribute(const std::string& file, const std::string& object, const std::string& name,
                        const std::string& value);
void setIntAttribute(const std::string& file, const std::string& object, const std::string& name,
                     std::int64_t value);
void deleteLink(const std::string& file, const std::string& path);
// Replaces a dataset by one of another type and shape, filled with zeros.
void replaceDataset(const std::string& file, const std::string& path, dem::h5::ElementType type,
                    const std::vector<std::uint64_t>& dims);
// The same as a chunked dataset that is never written: it declares `dims`
// but the file stays a few KB (what a hostile file declaring 10^8 bonds is).
void replaceWithSparseDataset(const std::string& file, const std::string& path,
                              dem::h5::ElementType type, const std::vector<std::uint64_t>& dims);
// Overwrites one element of an existing dataset (converted to its type).
void setElement(const std::string& file, const std::string& path, std::uint64_t index,
                double value);
void setInt32Elements(const std::string& file, const std::string& path,
                      const std::vector<std::int32_t>& values, std::uint64_t offset);
// Cuts the file to a fraction of its size.
void truncateFile(const std::string& file, double fraction);

}  // namespace crackvis::testing

namespace crackvis::testing {
void deleteAttribute(const std::string& file, const std::string& object, const std::string& name);
}  // namespace crackvis::testing

namespace crackvis::testing {
// Links that lead elsewhere: a soft link to `target` (a path in the same
// file), and an external link to `targetObject` in `targetFile`.
void addSoftLink(const std::string& file, const std::string& link, const std::string& target);
void addExternalLink(const std::string& file, const std::string& link,
                     const std::string& targetFile, const std::string& targetObject);
}  // namespace crackvis::testing
