// libFuzzer target: Read request validation and the piece plan of the data
// service's catalogue (dataservice/h5). The input is decoded into the
// hyperslabs of one Read (dataset names, starts and counts as a client may
// send them: negative, huge, wrong rank, names with NULs, links) against a
// fixed file made at start-up. Each request must be refused with a Status
// or planned into pieces that tile the slabs exactly, each at most one
// chunk; every piece is then read. What the service adds before the
// catalogue (slab count, path length, NUL) is checked by the same rules.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <mutex>
#include <string>
#include <vector>

#include <fuzzer/FuzzedDataProvider.h>
#include <hdf5.h>
#include <sys/stat.h>
#include <unistd.h>

#include "fuzz_require.hpp"
#include <crackvis/dataservice_h5/catalogue.hpp>
#include <crackvis/dem/h5.hpp>

const char* const kFuzzTargetName = "read request fuzzer";

namespace {

using namespace crackvis;
using namespace crackvis::dataservice;
namespace h5 = crackvis::dem::h5;

// What one execution may read at most, so that the fuzzer stays fast.
constexpr std::uint64_t kMaxReadBytes = std::uint64_t{8} << 20;
constexpr int kMaxSlabs = 8;

void writeValues(hid_t file, const char* name, h5::ElementType type,
                 const std::vector<std::uint64_t>& dims) {
  std::uint64_t count = 1;
  for (auto d : dims) {
    count *= d;
  }
  // Bytes enough for any element type; their values do not matter.
  std::vector<std::uint8_t> bytes(count * 8);
  for (std::uint64_t i = 0; i < bytes.size(); ++i) {
    bytes[i] = static_cast<std::uint8_t>(i % 251);
  }
  require(h5::writeDataset(file, name, type, dims, bytes.data()).isOk(), "fixture");
}

// The file every input reads: datasets of rank 0 to 3 (one whose rows are
// larger than a chunk), a sparse 1 GiB row, a group, soft links (one to a
// dataset, one to itself), an external link and a string dataset.
std::string makeFixture() {
  const char* folder = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
  const std::string root = std::string(folder) + "/crackvis-fuzz-read-" + std::to_string(getpid());
  mkdir(root.c_str(), 0700);
  const std::string path = root + "/fixture.h5";
  std::lock_guard lock(hdf5Mutex());
  h5::quietHdf5();
  h5::Handle file =
      h5::fileHandle(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
  require(file.valid(), "cannot create the fixture");
  const double scalar = 4.5;
  require(h5::writeDataset(file.get(), "scalar", h5::ElementType::kFloat64, {}, &scalar).isOk(),
          "fixture scalar");
  writeValues(file.get(), "v", h5::ElementType::kInt32, {1000});
  writeValues(file.get(), "m", h5::ElementType::kFloat64, {40, 2000});
  writeValues(file.get(), "t", h5::ElementType::kUInt8, {3, 700, 2000});
  h5::Handle group =
      h5::groupHandle(H5Gcreate2(file.get(), "g", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  writeValues(group.get(), "d", h5::ElementType::kFloat32, {5, 3});
  const hsize_t dims[2] = {1, hsize_t{1} << 27};
  const hsize_t chunk[2] = {1, hsize_t{1} << 16};
  h5::Handle space = h5::dataspaceHandle(H5Screate_simple(2, dims, nullptr));
  h5::Handle create = h5::propertyListHandle(H5Pcreate(H5P_DATASET_CREATE));
  H5Pset_chunk(create.get(), 2, chunk);
  h5::Handle sparse = h5::datasetHandle(H5Dcreate2(
      file.get(), "sparse", H5T_IEEE_F64LE, space.get(), H5P_DEFAULT, create.get(), H5P_DEFAULT));
  h5::Handle text = h5::datatypeHandle(H5Tcopy(H5T_C_S1));
  H5Tset_size(text.get(), 8);
  h5::Handle one = h5::dataspaceHandle(H5Screate(H5S_SCALAR));
  h5::Handle string = h5::datasetHandle(
      H5Dcreate2(file.get(), "str", text.get(), one.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  H5Lcreate_soft("/v", file.get(), "alias", H5P_DEFAULT, H5P_DEFAULT);
  H5Lcreate_soft("/loop", file.get(), "loop", H5P_DEFAULT, H5P_DEFAULT);
  H5Lcreate_external("/etc/other.h5", "/x", file.get(), "ext", H5P_DEFAULT, H5P_DEFAULT);
  return root;
}

const Catalogue& catalogue() {
  static const Catalogue instance(DataRoot::open(makeFixture()).value());
  return instance;
}

const char* const kNames[] = {"/scalar", "/v",    "/m",   "/t", "/g/d", "/sparse",  "/str",
                              "/alias",  "/loop", "/ext", "/g", "/",    "/missing", "v"};

std::string datasetName(FuzzedDataProvider& input) {
  if (input.ConsumeBool()) {
    return input.ConsumeRandomLengthString(64);  // anything, NULs included
  }
  return kNames[input.ConsumeIntegralInRange<std::size_t>(0, std::size(kNames) - 1)];
}

std::int64_t coordinate(FuzzedDataProvider& input) {
  switch (input.ConsumeIntegralInRange<int>(0, 3)) {
    case 0:
      return input.ConsumeIntegralInRange<std::int64_t>(0, 8);
    case 1:
      return input.ConsumeIntegralInRange<std::int64_t>(0, 3000);
    case 2:
      return input.ConsumeIntegralInRange<std::int64_t>(0, std::int64_t{1} << 28);
    default:
      return input.ConsumeIntegral<std::int64_t>();
  }
}

std::vector<Hyperslab> decodeSlabs(FuzzedDataProvider& input) {
  std::vector<Hyperslab> slabs(input.ConsumeIntegralInRange<int>(0, kMaxSlabs));
  for (Hyperslab& slab : slabs) {
    slab.dataset = datasetName(input);
    if (input.ConsumeBool()) {
      continue;  // the whole dataset
    }
    const int rank = input.ConsumeIntegralInRange<int>(0, 4);
    for (int d = 0; d < rank; ++d) {
      slab.start.push_back(coordinate(input));
      slab.count.push_back(coordinate(input));
    }
  }
  return slabs;
}

// The pieces tile each slab in order, none larger than a chunk.
void readAllPieces(SlabReader& reader) {
  std::vector<std::uint64_t> covered(reader.slabs().size(), 0);
  std::uint64_t total = 0;
  std::vector<char> buffer(kMaxChunkBytes);
  while (auto piece = reader.nextPiece()) {
    require(piece->slab < covered.size(), "a piece of no slab");
    require(piece->bytes > 0 && piece->bytes <= kMaxChunkBytes, "a piece larger than a chunk");
    require(piece->offset == covered[piece->slab], "pieces are not contiguous");
    covered[piece->slab] += piece->bytes;
    total += piece->bytes;
    const Status read = reader.read(*piece, buffer.data());
    if (!read) {
      std::fprintf(stderr, "%s\n", read.message().c_str());
    }
    require(read.isOk(), "a planned piece cannot be read");
  }
  for (std::size_t s = 0; s < covered.size(); ++s) {
    require(covered[s] == reader.slabs()[s].bytes, "the pieces do not cover their slab");
  }
  require(total == reader.totalBytes(), "the pieces do not add up to the total");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzedDataProvider input(data, size);
  const Catalogue& files = catalogue();
  const std::vector<Hyperslab> slabs = decodeSlabs(input);
  auto file = files.root().resolveFile("fixture.h5");
  require(file.isOk(), "the fixture is gone");
  auto reader = files.openRead(*file, slabs, kMaxReadBytes);
  if (!reader) {
    const StatusCode code = reader.status().code();
    require(code == StatusCode::kInvalidArgument || code == StatusCode::kNotFound ||
                code == StatusCode::kFailedPrecondition || code == StatusCode::kResourceExhausted ||
                code == StatusCode::kPermissionDenied || code == StatusCode::kOutOfRange,
            "a refusal with an unexpected code");
    require(reader.status().message().size() < 4096, "a refusal echoes too much");
    return 0;
  }
  readAllPieces(**reader);
  return 0;
}
