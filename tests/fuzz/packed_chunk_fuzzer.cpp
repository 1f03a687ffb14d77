// libFuzzer target: the PACKED chunk codec of the data service's Read
// (crackvis/dataservice_protocol/packed_chunk.hpp). Two halves, chosen by the first
// byte: (1) values of one packable type and 1-17 columns are packed and
// unpacked, each into a buffer of exactly its size; the values must come
// back bit for bit, and packing into exactly the packed size must give the
// same bytes; (2) hostile bytes are unpacked as a chunk of any decoded size
// (what a lying server could send): an error or some values, never a read
// or write outside the buffers.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <vector>

#include <fuzzer/FuzzedDataProvider.h>

#include "fuzz_require.hpp"
#include <crackvis/dataservice_protocol/packed_chunk.hpp>

const char* const kFuzzTargetName = "packed chunk fuzzer";

namespace {

using namespace crackvis;
using namespace crackvis::dataservice;

constexpr DataType kTypes[] = {DataType::kInt8,   DataType::kUInt8, DataType::kInt16,
                               DataType::kUInt16, DataType::kInt32, DataType::kUInt32,
                               DataType::kFloat32};

void roundTrip(FuzzedDataProvider& input) {
  const DataType dtype = input.PickValueInArray(kTypes);
  const auto columns = input.ConsumeIntegralInRange<std::size_t>(1, kMaxPackedColumns + 1);
  std::vector<std::uint8_t> values = input.ConsumeRemainingBytes<std::uint8_t>();
  const std::size_t row = columns * elementSize(dtype);
  values.resize(values.size() / row * row);
  const auto* raw = reinterpret_cast<const std::byte*>(values.data());
  std::vector<std::byte> roomy(values.size() + 64);
  const std::size_t size =
      packChunk(dtype, columns, raw, values.size(), roomy.data(), roomy.size());
  if (size == 0) {
    return;  // sent raw: nothing to check
  }
  require(packableType(dtype) && columns <= kMaxPackedColumns, "packed what it may not");
  require(size < values.size(), "packed to no fewer bytes");
  std::vector<std::byte> exact(size);
  require(packChunk(dtype, columns, raw, values.size(), exact.data(), exact.size()) == size,
          "another size into an exact buffer");
  require(std::memcmp(exact.data(), roomy.data(), size) == 0, "other bytes into an exact buffer");
  std::vector<std::byte> back(values.size());
  const Status status = unpackChunk(dtype, exact.data(), exact.size(), back.data(), back.size());
  if (!status.isOk()) {
    std::fprintf(stderr, "%s\n", status.message().c_str());
  }
  require(status.isOk(), "its own chunk refused");
  require(std::memcmp(back.data(), values.data(), values.size()) == 0, "values changed");
}

void unpackHostile(FuzzedDataProvider& input) {
  const DataType dtype = input.PickValueInArray(kTypes);
  const auto rawBytes = input.ConsumeIntegralInRange<std::size_t>(0, 1 << 16);
  const std::vector<std::uint8_t> chunk = input.ConsumeRemainingBytes<std::uint8_t>();
  std::vector<std::byte> packed(chunk.size());
  if (!chunk.empty()) {
    std::memcpy(packed.data(), chunk.data(), chunk.size());
  }
  std::vector<std::byte> out(rawBytes);
  const Status status = unpackChunk(dtype, packed.data(), packed.size(), out.data(), out.size());
  require(status.isOk() || status.code() == StatusCode::kInvalidArgument,
          "a refusal that is not INVALID_ARGUMENT");
  require(status.message().size() < 300, "a refusal of over 300 characters");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  FuzzedDataProvider input(data, size);
  if (input.ConsumeBool()) {
    roundTrip(input);
  } else {
    unpackHostile(input);
  }
  return 0;
}
