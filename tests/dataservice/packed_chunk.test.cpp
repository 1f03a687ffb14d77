// The PACKED chunk encoding (crackvis/dataservice_protocol/packed_chunk.hpp): every
// packable type and column count comes back exactly, a chunk is packed only
// when that makes it smaller, and a malformed chunk is an error, never a
// read outside it.
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include <catch2/catch.hpp>

#include <crackvis/dataservice_protocol/packed_chunk.hpp>

namespace crackvis::testing {
namespace {

using dataservice::DataType;
using dataservice::kMaxChunkBytes;
using dataservice::packChunk;
using dataservice::unpackChunk;

template <typename T>
std::vector<std::byte> bytesOf(const std::vector<T>& values) {
  std::vector<std::byte> bytes(values.size() * sizeof(T));
  if (!bytes.empty()) {
    std::memcpy(bytes.data(), values.data(), bytes.size());
  }
  return bytes;
}

// Packs and unpacks; returns the packed size (0: sent as it is).
std::size_t roundTrip(DataType dtype, std::size_t columns, const std::vector<std::byte>& raw) {
  std::vector<std::byte> packed(kMaxChunkBytes);
  const std::size_t size =
      packChunk(dtype, columns, raw.data(), raw.size(), packed.data(), packed.size());
  if (size == 0) {
    return 0;
  }
  CHECK(size < raw.size());
  // Again into a buffer of exactly that size: nothing written beyond it
  // (ASan would say), and the same bytes.
  std::vector<std::byte> exact(size);
  CHECK(packChunk(dtype, columns, raw.data(), raw.size(), exact.data(), exact.size()) == size);
  packed.resize(size);
  CHECK(exact == packed);
  packed.shrink_to_fit();  // an exact fit: nothing read beyond it either
  std::vector<std::byte> back(raw.size(), std::byte{0x5a});
  const Status status = unpackChunk(dtype, packed.data(), size, back.data(), back.size());
  INFO(status.message());
  REQUIRE(status.isOk());
  CHECK(back == raw);
  return size;
}

// A bond list of a cubic lattice: sorted by first particle, neighbours a
// few indices or a row or a plane away.
std::vector<std::int32_t> latticePairs(int side) {
  std::vector<std::int32_t> pairs;
  for (int i = 0; i < side * side * side; ++i) {
    for (int step : {1, side, side * side}) {
      if (i + step < side * side * side) {
        pairs.push_back(i);
        pairs.push_back(i + step);
      }
    }
  }
  return pairs;
}

TEST_CASE("Packed chunks come back exactly, for every packable type and row length",
          "[dataservice]") {
  std::mt19937 random(7);
  SECTION("a lattice's bond list: about 12 bits a bond instead of 64") {
    const auto pairs = latticePairs(40);  // 187,200 bonds, rows of 2
    const auto raw = bytesOf(pairs);
    const std::size_t count = pairs.size() / 2;
    const std::size_t packed = roundTrip(DataType::kInt32, 2, raw);
    REQUIRE(packed > 0);
    // Column 0 from the previous row (0 or 1: 1 bit), column 1 from column
    // 0 (1 .. 1600: 11 bits), plus the header.
    CHECK(packed <= (count * 12) / 8 + 64);
  }

  SECTION("bond states of 0 and 1: one bit each") {
    std::vector<std::uint8_t> states(100'003);
    for (auto& s : states) {
      s = random() % 7 == 0 ? 1 : 0;
    }
    const std::size_t packed = roundTrip(DataType::kUInt8, 1, bytesOf(states));
    CHECK(packed == 1 + 18 + (states.size() + 7) / 8 + 8);
  }

  SECTION("every type, 1 to 5 columns, row counts around the groups of eight") {
    for (const std::size_t rows : {1, 7, 8, 9, 63, 1000, 4097}) {
      for (const std::size_t columns : {1, 2, 3, 5}) {
        INFO(rows << " rows of " << columns);
        std::uniform_int_distribution<int> small(-3, 40);
        std::vector<std::int8_t> i8(rows * columns);
        std::vector<std::uint16_t> u16(rows * columns);
        std::vector<std::int16_t> i16(rows * columns);
        std::vector<std::uint32_t> u32(rows * columns);
        std::vector<std::int32_t> i32(rows * columns);
        std::vector<std::uint8_t> u8(rows * columns);
        for (std::size_t k = 0; k < rows * columns; ++k) {
          const int v = small(random);
          i8[k] = static_cast<std::int8_t>(v);
          u8[k] = static_cast<std::uint8_t>(200 + v);
          i16[k] = static_cast<std::int16_t>(-30000 + static_cast<int>(k % 50) * v);
          u16[k] = static_cast<std::uint16_t>(60000 + v);
          i32[k] = static_cast<std::int32_t>(k / columns) * 3 + v - 2'000'000'000;
          u32[k] = 4'000'000'000u + static_cast<std::uint32_t>(k) + static_cast<std::uint32_t>(v);
        }
        roundTrip(DataType::kInt8, columns, bytesOf(i8));
        roundTrip(DataType::kUInt8, columns, bytesOf(u8));
        roundTrip(DataType::kInt16, columns, bytesOf(i16));
        roundTrip(DataType::kUInt16, columns, bytesOf(u16));
        roundTrip(DataType::kInt32, columns, bytesOf(i32));
        roundTrip(DataType::kUInt32, columns, bytesOf(u32));
      }
    }
  }

  SECTION("signed 16-bit values either side of zero, as differences") {
    // Column 1 a little below column 0, crossing zero: stored from column 0
    // in 4 bits (an int16 -1 once widened as 0xffff made these wrong); and a
    // column rising through zero, stored from the previous row.
    std::vector<std::int16_t> nearby;
    std::vector<std::int16_t> rising;
    for (int r = 0; r < 100; ++r) {  // column 0 positive, column 1 negative
      nearby.push_back(static_cast<std::int16_t>(100 + 37 * r));
      nearby.push_back(static_cast<std::int16_t>(100 + 37 * r - 6000 + r % 16));
    }
    for (int r = 0; r < 200; ++r) {
      rising.push_back(static_cast<std::int16_t>(-500 + 5 * r + r % 3));
    }
    CHECK(roundTrip(DataType::kInt16, 2, bytesOf(nearby)) > 0);
    CHECK(roundTrip(DataType::kInt16, 1, bytesOf(rising)) > 0);
    std::vector<std::int32_t> crossing;
    for (int r = 0; r < 300; ++r) {
      crossing.push_back(r * 3 - 450);
      crossing.push_back(r * 3 - 450 - (r % 7));
    }
    CHECK(roundTrip(DataType::kInt32, 2, bytesOf(crossing)) > 0);
  }

  SECTION("values spanning 2^31 and more (64-bit differences), and the extremes") {
    std::vector<std::int32_t> wide;
    std::vector<std::uint32_t> unsignedWide;
    for (int r = 0; r < 5000; ++r) {
      wide.push_back(r % 2 == 0 ? std::numeric_limits<std::int32_t>::min() + r
                                : std::numeric_limits<std::int32_t>::max() - r);
      wide.push_back(r);
      unsignedWide.push_back(r % 3 == 0 ? 0u : 0xffffffffu - static_cast<std::uint32_t>(r));
    }
    // Differences need 33 bits: no smaller, or barely; exact either way.
    roundTrip(DataType::kInt32, 2, bytesOf(wide));
    roundTrip(DataType::kUInt32, 1, bytesOf(unsignedWide));
    // A constant column packs to no bits at all.
    std::vector<std::int32_t> constant(10'000, -123456);
    CHECK(roundTrip(DataType::kInt32, 1, bytesOf(constant)) == 1 + 18 + 8);
  }

  SECTION("a chunk that would not shrink, or cannot be packed, goes as it is") {
    std::vector<std::uint32_t> noise(4096);
    for (auto& v : noise) {
      v = static_cast<std::uint32_t>(random());
    }
    std::vector<std::byte> out(kMaxChunkBytes);
    const auto raw = bytesOf(noise);
    CHECK(packChunk(DataType::kUInt32, 1, raw.data(), raw.size(), out.data(), out.size()) == 0);
    const std::vector<double> reals(100, 1.0);
    const auto realBytes = bytesOf(reals);
    CHECK(packChunk(DataType::kFloat64, 1, realBytes.data(), realBytes.size(), out.data(),
                    out.size()) == 0);
    const std::vector<std::int64_t> wide64(100, 1);
    const auto wideBytes = bytesOf(wide64);
    CHECK(packChunk(DataType::kInt64, 1, wideBytes.data(), wideBytes.size(), out.data(),
                    out.size()) == 0);
    const auto sevenPairs = bytesOf(std::vector<std::int32_t>(14, 3));  // 56 bytes
    CHECK(packChunk(DataType::kInt32, 3, sevenPairs.data(), sevenPairs.size(), out.data(),
                    out.size()) == 0);  // not whole rows of 3
    const auto pairs = bytesOf(latticePairs(10));
    CHECK(packChunk(DataType::kInt32, 17, pairs.data(), pairs.size(), out.data(), out.size()) ==
          0);  // over kMaxPackedColumns
    CHECK(packChunk(DataType::kInt32, 2, pairs.data(), pairs.size(), out.data(), 100) == 0);
  }
}

TEST_CASE("A malformed packed chunk is refused, saying what is wrong", "[dataservice]") {
  const auto pairs = latticePairs(12);
  const auto raw = bytesOf(pairs);
  std::vector<std::byte> packed(kMaxChunkBytes);
  const std::size_t size =
      packChunk(DataType::kInt32, 2, raw.data(), raw.size(), packed.data(), packed.size());
  REQUIRE(size > 0);
  packed.resize(size);
  std::vector<std::byte> out(raw.size());
  const auto unpack = [&](std::vector<std::byte> chunk, std::size_t rawBytes) {
    return unpackChunk(DataType::kInt32, chunk.data(), chunk.size(), out.data(), rawBytes);
  };
  const auto with = [&](std::size_t at, std::uint8_t value) {
    auto changed = packed;
    changed[at] = std::byte{value};
    return changed;
  };
  const std::vector<std::pair<Status, std::string>> cases = {
      {unpack({}, raw.size()), "empty"},
      {unpack(with(0, 0), raw.size()), "0 columns"},
      {unpack(with(0, 17), raw.size()), "17 columns"},
      {unpack(packed, raw.size() - 4), "no whole rows"},
      {unpack(with(1, 3), raw.size()), "column 0 has form 3"},
      {unpack(with(1, 2), raw.size()), "column 0 has form 2"},
      {unpack(with(2, 34), raw.size()), "34 bits"},
      {unpack({packed.begin(), packed.end() - 1}, raw.size()), "where its header"},
      {unpack({packed.begin(), packed.begin() + 20}, raw.size()), "shorter than its header"},
      {unpack(packed, raw.size() - 8), "where its header"},  // fewer rows than it holds
  };
  for (const auto& [status, expected] : cases) {
    CHECK(status.code() == StatusCode::kInvalidArgument);
    CHECK_THAT(status.message(), Catch::Contains(expected));
  }
  CHECK(unpackChunk(DataType::kFloat32, packed.data(), packed.size(), out.data(), raw.size())
            .code() == StatusCode::kInvalidArgument);

  // Any byte changed: a refusal naming what is wrong, or values that are a
  // chunk's own (packed again, they unpack to the same values); a chunk cut
  // short: a refusal. Never a read or write outside the buffers (ASan and
  // the exact-size copies watch).
  std::mt19937 random(11);
  int refused = 0;
  int decoded = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    auto changed = packed;
    const std::size_t at = random() % changed.size();
    const bool cut = trial % 2 == 1;
    if (cut) {
      changed.resize(at);
    } else {
      changed[at] = static_cast<std::byte>(random());
    }
    std::vector<std::byte> exact(changed);
    std::vector<std::byte> values(raw.size());
    const Status status =
        unpackChunk(DataType::kInt32, exact.data(), exact.size(), values.data(), values.size());
    INFO("trial " << trial << ": byte " << at << ": " << status.message());
    CHECK_FALSE((cut && status.isOk()));
    if (!status.isOk()) {
      ++refused;
      CHECK(status.code() == StatusCode::kInvalidArgument);
      CHECK_FALSE(status.message().empty());
      CHECK(status.message().size() < 200);
      continue;
    }
    ++decoded;
    std::vector<std::byte> repacked(kMaxChunkBytes);
    const std::size_t size = packChunk(DataType::kInt32, 2, values.data(), values.size(),
                                       repacked.data(), repacked.size());
    if (size == 0) {
      continue;  // values that do not pack smaller travel as they are
    }
    std::vector<std::byte> again(values.size());
    REQUIRE(
        unpackChunk(DataType::kInt32, repacked.data(), size, again.data(), again.size()).isOk());
    CHECK(again == values);
  }
  // Every cut chunk was refused; a changed byte mostly decodes to other
  // values (the header is a few bytes of it).
  CHECK(refused >= 1000);
  CHECK(decoded > 0);
}

}  // namespace
}  // namespace crackvis::testing
