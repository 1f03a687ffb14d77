// The PACKED chunk encoding of crackvis-data's Read (docs/protocol.md,
// "Packed chunks"): integer arrays sent as a few bits per value instead of
// their full width, losslessly. A view's first Read is half bond list (int32
// [M,2], 8 bytes a bond); its pairs of nearby particles need about 12 bits a
// bond, and a bond state (uint8, 0 or 1) one bit.
//
// A chunk's values are taken as `columns` interleaved sequences (the last
// dimension of an [M,2] list: column 0 the first particle, column 1 the
// second). Each column is stored in one of three forms, whichever needs the
// fewest bits: as it is, as differences from the previous row (sorted
// indices), or as differences from column 0 of the same row (a bond's second
// particle near its first). The form's values minus their minimum are
// bit-packed at a fixed width per column (frame of reference). Used by the
// server (packChunk) and the client library (unpackChunk); gRPC-free.
//
// Layout, little-endian:
//   u8 columns (1..16)
//   per column: u8 form, u8 bits (0..33), i64 first (the value before row 0,
//               for differences from the previous row), i64 minimum
//   per column: ceil(rows * bits / 8) bytes, value r at bit r * bits
//   8 zero bytes (so that a decoder may load 8 bytes at any value's byte)
#pragma once

#include <cstddef>
#include <cstdint>

#include <crackvis/common/status.hpp>
#include <crackvis/dataservice_protocol/types.hpp>

namespace crackvis::dataservice {

// Whether a dtype can be packed: integers of at most 32 bits (the
// differences of wider ones may not fit the arithmetic).
bool packableType(DataType dtype);

// The most columns a chunk may declare.
inline constexpr std::size_t kMaxPackedColumns = 16;

// Packs `rawBytes` of `dtype` values, `columns` to a row, into `out`
// (`capacity` bytes). Returns the packed size, or 0 when packing would not
// make the chunk smaller (or the type, column count or size do not allow
// it): the chunk then goes as it is. Nothing beyond the returned size is
// written; with a smaller result nothing at all.
std::size_t packChunk(DataType dtype, std::size_t columns, const std::byte* raw,
                      std::size_t rawBytes, std::byte* out, std::size_t capacity);

// Unpacks a chunk into exactly `rawBytes` bytes at `out`. A chunk that is
// malformed for that size (wrong length, column count, form or width) is
// INVALID_ARGUMENT naming what is wrong; nothing is read outside `packed`.
Status unpackChunk(DataType dtype, const std::byte* packed, std::size_t packedBytes, std::byte* out,
                   std::size_t rawBytes);

}  // namespace crackvis::dataservice
