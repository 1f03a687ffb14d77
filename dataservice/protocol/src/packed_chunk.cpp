#include <array>
#include <bit>
#include <cstring>
#include <limits>
#include <type_traits>

#include <fmt/format.h>

#include <crackvis/dataservice_protocol/packed_chunk.hpp>

namespace crackvis::dataservice {

namespace {

static_assert(std::endian::native == std::endian::little,
              "packed chunks are little-endian; a big-endian host must swap them");

// How a column's values are taken before packing.
enum class Form : std::uint8_t {
  kAsIs = 0,          // the values
  kFromPrevious = 1,  // minus the previous row's value (row 0: minus `first`)
  kFromColumn0 = 2,   // minus column 0 of the same row
};
constexpr int kForms = 3;

// Calls f with the form as a compile-time constant: each form's loop is
// compiled on its own, without a branch per value.
template <typename F>
void withForm(Form form, F&& f) {
  switch (form) {
    case Form::kAsIs:
      f(std::integral_constant<Form, Form::kAsIs>{});
      break;
    case Form::kFromPrevious:
      f(std::integral_constant<Form, Form::kFromPrevious>{});
      break;
    case Form::kFromColumn0:
      f(std::integral_constant<Form, Form::kFromColumn0>{});
      break;
  }
}

// Calls f with a value of the C++ type of a packable dtype, `otherwise()`
// for any other.
template <typename F, typename G>
auto withPackableType(DataType dtype, F&& f, G&& otherwise) {
  switch (dtype) {
    case DataType::kInt8:
      return f(std::int8_t{});
    case DataType::kUInt8:
      return f(std::uint8_t{});
    case DataType::kInt16:
      return f(std::int16_t{});
    case DataType::kUInt16:
      return f(std::uint16_t{});
    case DataType::kInt32:
      return f(std::int32_t{});
    case DataType::kUInt32:
      return f(std::uint32_t{});
    default:
      return otherwise();
  }
}
// Differences of 32-bit values span less than 2^33.
constexpr unsigned kMaxBits = 33;
constexpr std::size_t kColumnHeaderBytes = 1 + 1 + 8 + 8;
constexpr std::size_t kPaddingBytes = 8;

// A value of type T at `at` (any alignment), and the same widened.
template <typename T>
T loadAs(const std::byte* at) {
  T value;
  std::memcpy(&value, at, sizeof(T));
  return value;
}

template <typename T>
std::int64_t load(const std::byte* at) {
  return static_cast<std::int64_t>(loadAs<T>(at));
}

template <typename T>
void store(std::byte* at, std::uint64_t value) {
  // Conversion to an unsigned type wraps, then the bits are the value's.
  using Unsigned = std::make_unsigned_t<T>;
  const auto narrowed = static_cast<Unsigned>(value);
  std::memcpy(at, &narrowed, sizeof(T));
}

std::uint64_t load64(const std::byte* at) {
  std::uint64_t word;
  std::memcpy(&word, at, sizeof(word));
  return word;
}

unsigned bitsFor(std::int64_t low, std::int64_t high) {
  return static_cast<unsigned>(std::bit_width(static_cast<std::uint64_t>(high - low)));
}

std::size_t packedColumnBytes(std::size_t rows, unsigned bits) {
  return (rows * bits + 7) / 8;
}

struct Range {
  std::int64_t low = std::numeric_limits<std::int64_t>::max();
  std::int64_t high = std::numeric_limits<std::int64_t>::min();
  void add(std::int64_t value) {
    low = std::min(low, value);
    high = std::max(high, value);
  }
};

struct ColumnPlan {
  Form form = Form::kAsIs;
  unsigned bits = 0;
  std::int64_t first = 0;
  std::int64_t minimum = 0;
};

// The plan's passes are simple min/max reductions that vectorize when the
// row stride is known at compile time; on x86-64 each is also built for
// AVX2 and picked at load time (baseline SSE2 has no 32-bit min/max), which
// makes planning a bond list's chunk about 8x faster.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define CRACKVIS_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define CRACKVIS_VECTOR_CLONES
#endif

// A column's values as they are. kColumns: the row length when known at
// compile time, else 0 and `columns` gives it.
template <typename T, std::size_t kColumns>
CRACKVIS_VECTOR_CLONES Range asIsRange(const std::byte* raw, std::size_t columns, std::size_t rows,
                                       std::size_t column) {
  const std::size_t stride = (kColumns != 0 ? kColumns : columns) * sizeof(T);
  const std::byte* at = raw + column * sizeof(T);
  T low = std::numeric_limits<T>::max();
  T high = std::numeric_limits<T>::min();
  for (std::size_t r = 0; r < rows; ++r) {
    const T value = loadAs<T>(at + r * stride);
    low = std::min(low, value);
    high = std::max(high, value);
  }
  return {low, high};
}

// A column's differences from the previous row and from column 0, in 32-bit
// arithmetic: exact when every value of both columns lies within a span
// below 2^31 (the caller checks), whatever the values themselves.
template <typename T, std::size_t kColumns>
CRACKVIS_VECTOR_CLONES void differenceRanges(const std::byte* raw, std::size_t columns,
                                             std::size_t rows, std::size_t column,
                                             Range& fromPrevious, Range& fromColumn0) {
  const std::size_t stride = (kColumns != 0 ? kColumns : columns) * sizeof(T);
  const std::byte* at = raw + column * sizeof(T);
  // Each value widened with its sign (int16 -1 is 0xffffffff, not 0xffff),
  // subtracted modulo 2^32: the true difference whenever it fits 32 bits.
  const auto difference = [](T a, T b) {
    return static_cast<std::int32_t>(static_cast<std::uint32_t>(a) - static_cast<std::uint32_t>(b));
  };
  std::int32_t low = 0;  // row 0 differs from `first`, itself, by 0
  std::int32_t high = 0;
  for (std::size_t r = 1; r < rows; ++r) {
    const std::int32_t d = difference(loadAs<T>(at + r * stride), loadAs<T>(at + (r - 1) * stride));
    low = std::min(low, d);
    high = std::max(high, d);
  }
  fromPrevious = {low, high};
  if (column == 0) {
    return;
  }
  low = std::numeric_limits<std::int32_t>::max();
  high = std::numeric_limits<std::int32_t>::min();
  for (std::size_t r = 0; r < rows; ++r) {
    const std::int32_t d = difference(loadAs<T>(at + r * stride), loadAs<T>(raw + r * stride));
    low = std::min(low, d);
    high = std::max(high, d);
  }
  fromColumn0 = {low, high};
}

// The same in 64-bit arithmetic, one row at a time: for columns spanning
// 2^31 or more (32-bit values only).
template <typename T>
void wideDifferenceRanges(const std::byte* raw, std::size_t columns, std::size_t rows,
                          std::size_t column, Range& fromPrevious, Range& fromColumn0) {
  const std::size_t stride = columns * sizeof(T);
  const std::byte* at = raw + column * sizeof(T);
  std::int64_t previous = load<T>(at);
  for (std::size_t r = 0; r < rows; ++r, at += stride) {
    const std::int64_t value = load<T>(at);
    fromPrevious.add(value - previous);
    if (column > 0) {
      fromColumn0.add(value - load<T>(at - column * sizeof(T)));
    }
    previous = value;
  }
}

template <typename T, std::size_t kColumns>
void columnRanges(const std::byte* raw, std::size_t columns, std::size_t rows, std::size_t column,
                  std::array<Range, kForms>& ranges) {
  ranges[0] = asIsRange<T, kColumns>(raw, columns, rows, column);
  if constexpr (sizeof(T) == 1) {
    return;  // 8-bit values are taken as they are: their differences need 9 bits
  } else {
    const Range column0 = column == 0 ? ranges[0] : asIsRange<T, kColumns>(raw, columns, rows, 0);
    constexpr std::int64_t kNarrow = std::int64_t{1} << 31;
    if (ranges[0].high - ranges[0].low < kNarrow && column0.high - column0.low < kNarrow &&
        std::max(ranges[0].high, column0.high) - std::min(ranges[0].low, column0.low) < kNarrow) {
      differenceRanges<T, kColumns>(raw, columns, rows, column, ranges[1], ranges[2]);
    } else {
      wideDifferenceRanges<T>(raw, columns, rows, column, ranges[1], ranges[2]);
    }
  }
}

// The form of a column that needs the fewest bits.
template <typename T>
ColumnPlan planColumn(const std::byte* raw, std::size_t columns, std::size_t rows,
                      std::size_t column) {
  std::array<Range, kForms> ranges;
  switch (columns) {
    case 1:
      columnRanges<T, 1>(raw, columns, rows, column, ranges);
      break;
    case 2:
      columnRanges<T, 2>(raw, columns, rows, column, ranges);
      break;
    case 3:
      columnRanges<T, 3>(raw, columns, rows, column, ranges);
      break;
    default:
      columnRanges<T, 0>(raw, columns, rows, column, ranges);
      break;
  }
  ColumnPlan best;
  best.first = load<T>(raw + column * sizeof(T));
  best.bits = kMaxBits + 1;
  const int forms = sizeof(T) == 1 ? 1 : (column > 0 ? kForms : 2);
  for (int f = 0; f < forms; ++f) {
    const unsigned bits = bitsFor(ranges[f].low, ranges[f].high);
    if (bits < best.bits) {
      best.form = static_cast<Form>(f);
      best.bits = bits;
      best.minimum = ranges[f].low;
    }
  }
  return best;
}

// A column's value at `at` in its form, minus the column's minimum: what is
// packed.
template <typename T, Form form>
std::uint64_t packedValue(const std::byte* at, std::size_t column, std::int64_t& previous,
                          std::int64_t minimum) {
  std::int64_t value = load<T>(at);
  if constexpr (form == Form::kFromPrevious) {
    const std::int64_t difference = value - previous;
    previous = value;
    value = difference;
  } else if constexpr (form == Form::kFromColumn0) {
    value -= load<T>(at - column * sizeof(T));
  }
  return static_cast<std::uint64_t>(value - minimum);
}

// Writes a column's values at `bits` each, low bits first, into `out`,
// which is zeroed and has 8 bytes to spare. Eight values of at most 8 bits
// fill `bits` whole bytes and go as one word.
template <typename T, Form form>
void packColumnAs(const std::byte* raw, std::size_t columns, std::size_t rows, std::size_t column,
                  const ColumnPlan& plan, std::byte* out) {
  const std::size_t stride = columns * sizeof(T);
  const std::byte* at = raw + column * sizeof(T);
  const unsigned bits = plan.bits;
  std::int64_t previous = plan.first;
  std::size_t r = 0;
  if (bits <= 8) {
    std::byte* group = out;
    for (; r + 8 <= rows; r += 8, group += bits) {
      std::uint64_t word = 0;
      for (unsigned k = 0; k < 8; ++k, at += stride) {
        word |= packedValue<T, form>(at, column, previous, plan.minimum) << (k * bits);
      }
      std::memcpy(group, &word, sizeof(word));
    }
  }
  // The rest: the bits not yet in whole bytes stay in `word` (at most 7 of
  // them, then a value of at most 33); every value stores the word whole and
  // moves on by the bytes it completed. Stores only: reading the stream
  // back would stall on each store.
  const std::size_t bit = r * bits;
  std::byte* cursor = out + bit / 8;
  unsigned filled = bit % 8;
  std::uint64_t word = filled == 0 ? 0 : std::to_integer<std::uint64_t>(*cursor);
  for (; r < rows; ++r, at += stride) {
    word |= packedValue<T, form>(at, column, previous, plan.minimum) << filled;
    filled += bits;
    std::memcpy(cursor, &word, sizeof(word));
    const unsigned done = filled / 8;
    cursor += done;
    word >>= done * 8;  // done <= 5
    filled -= done * 8;
  }
}

template <typename T>
std::byte* packColumn(const std::byte* raw, std::size_t columns, std::size_t rows,
                      std::size_t column, const ColumnPlan& plan, std::byte* out) {
  if (plan.bits == 0) {
    return out;  // every value is the minimum
  }
  withForm(plan.form, [&](auto form) {
    packColumnAs<T, decltype(form)::value>(raw, columns, rows, column, plan, out);
  });
  return out + packedColumnBytes(rows, plan.bits);
}

template <typename T>
std::size_t packTyped(std::size_t columns, const std::byte* raw, std::size_t rawBytes,
                      std::byte* out, std::size_t capacity) {
  const std::size_t rows = rawBytes / (columns * sizeof(T));
  std::array<ColumnPlan, kMaxPackedColumns> plans;
  std::size_t size = 1 + columns * kColumnHeaderBytes + kPaddingBytes;
  for (std::size_t c = 0; c < columns; ++c) {
    plans[c] = planColumn<T>(raw, columns, rows, c);
    size += packedColumnBytes(rows, plans[c].bits);
  }
  if (size >= rawBytes || size > capacity) {
    return 0;
  }
  std::memset(out, 0, size);
  std::byte* at = out;
  *at++ = static_cast<std::byte>(columns);
  for (std::size_t c = 0; c < columns; ++c) {
    *at++ = static_cast<std::byte>(plans[c].form);
    *at++ = static_cast<std::byte>(plans[c].bits);
    std::memcpy(at, &plans[c].first, 8);
    std::memcpy(at + 8, &plans[c].minimum, 8);
    at += 16;
  }
  for (std::size_t c = 0; c < columns; ++c) {
    at = packColumn<T>(raw, columns, rows, c, plans[c], at);
  }
  return size;
}

// The inverse of packColumnAs, with the same wrapping arithmetic: the
// encoder's differences come back exactly in the value's width, and a
// hostile chunk cannot overflow anything.
template <typename T, Form form>
void unpackColumnAs(const std::byte* bits, std::size_t columns, std::size_t rows,
                    std::size_t column, const ColumnPlan& plan, std::byte* out) {
  const std::size_t stride = columns * sizeof(T);
  const unsigned width = plan.bits;
  const std::uint64_t mask = width == 0 ? 0 : (std::uint64_t{1} << width) - 1;
  const auto minimum = static_cast<std::uint64_t>(plan.minimum);
  auto previous = static_cast<std::uint64_t>(plan.first);
  std::byte* at = out + column * sizeof(T);
  const auto put = [&](std::uint64_t packed) {
    std::uint64_t value = packed + minimum;
    if constexpr (form == Form::kFromPrevious) {
      value += previous;
      previous = value;
    } else if constexpr (form == Form::kFromColumn0) {
      value += static_cast<std::uint64_t>(load<T>(at - column * sizeof(T)));
    }
    store<T>(at, value);
    at += stride;
  };
  std::size_t r = 0;
  if (width <= 8) {
    const std::byte* group = bits;
    for (; r + 8 <= rows; r += 8, group += width) {
      const std::uint64_t word = load64(group);
      for (unsigned k = 0; k < 8; ++k) {
        put((word >> (k * width)) & mask);
      }
    }
  }
  for (std::size_t bit = r * width; r < rows; ++r, bit += width) {
    put((load64(bits + bit / 8) >> (bit % 8)) & mask);
  }
}

template <typename T>
void unpackColumn(const std::byte* bits, std::size_t columns, std::size_t rows, std::size_t column,
                  const ColumnPlan& plan, std::byte* out) {
  withForm(plan.form, [&](auto form) {
    unpackColumnAs<T, decltype(form)::value>(bits, columns, rows, column, plan, out);
  });
}

template <typename T>
Status unpackTyped(const std::byte* packed, std::size_t packedBytes, std::byte* out,
                   std::size_t rawBytes) {
  if (packedBytes < 1) {
    return invalidArgument("packed chunk: empty");
  }
  const std::size_t columns = std::to_integer<std::size_t>(packed[0]);
  if (columns < 1 || columns > kMaxPackedColumns) {
    return invalidArgument(
        fmt::format("packed chunk: {} columns (1..{})", columns, kMaxPackedColumns));
  }
  if (rawBytes % (columns * sizeof(T)) != 0) {
    return invalidArgument(
        fmt::format("packed chunk: {} bytes are no whole rows of {} {}-byte values", rawBytes,
                    columns, sizeof(T)));
  }
  const std::size_t rows = rawBytes / (columns * sizeof(T));
  std::size_t size = 1 + columns * kColumnHeaderBytes + kPaddingBytes;
  if (packedBytes < size) {
    return invalidArgument(
        fmt::format("packed chunk: {} bytes, shorter than its header", packedBytes));
  }
  std::array<ColumnPlan, kMaxPackedColumns> plans;
  const std::byte* at = packed + 1;
  for (std::size_t c = 0; c < columns; ++c, at += kColumnHeaderBytes) {
    const auto form = std::to_integer<unsigned>(at[0]);
    const auto bits = std::to_integer<unsigned>(at[1]);
    if (form >= kForms || (c == 0 && form == static_cast<unsigned>(Form::kFromColumn0))) {
      return invalidArgument(fmt::format("packed chunk: column {} has form {}", c, form));
    }
    if (bits > kMaxBits) {
      return invalidArgument(
          fmt::format("packed chunk: column {} has {} bits (at most {})", c, bits, kMaxBits));
    }
    plans[c].form = static_cast<Form>(form);
    plans[c].bits = bits;
    std::memcpy(&plans[c].first, at + 2, 8);
    std::memcpy(&plans[c].minimum, at + 10, 8);
    size += packedColumnBytes(rows, bits);
  }
  if (packedBytes != size) {
    return invalidArgument(fmt::format(
        "packed chunk: {} bytes where its header and {} rows make {}", packedBytes, rows, size));
  }
  if (rows == 0) {
    return Status::ok();  // nothing to write (and `out` may be null)
  }
  for (std::size_t c = 0; c < columns; ++c) {
    unpackColumn<T>(at, columns, rows, c, plans[c], out);
    at += packedColumnBytes(rows, plans[c].bits);
  }
  return Status::ok();
}

}  // namespace

bool packableType(DataType dtype) {
  return withPackableType(
      dtype, [](auto) { return true; }, [] { return false; });
}

std::size_t packChunk(DataType dtype, std::size_t columns, const std::byte* raw,
                      std::size_t rawBytes, std::byte* out, std::size_t capacity) {
  if (!packableType(dtype) || columns < 1 || columns > kMaxPackedColumns || rawBytes == 0 ||
      rawBytes % (columns * elementSize(dtype)) != 0) {
    return 0;
  }
  return withPackableType(
      dtype,
      [&](auto value) { return packTyped<decltype(value)>(columns, raw, rawBytes, out, capacity); },
      [] { return std::size_t{0}; });
}

Status unpackChunk(DataType dtype, const std::byte* packed, std::size_t packedBytes, std::byte* out,
                   std::size_t rawBytes) {
  return withPackableType(
      dtype,
      [&](auto value) { return unpackTyped<decltype(value)>(packed, packedBytes, out, rawBytes); },
      [&] {
        return invalidArgument(fmt::format(
            "packed chunk of {}: only integers of up to 32 bits are packed", dataTypeName(dtype)));
      });
}

}  // namespace crackvis::dataservice
