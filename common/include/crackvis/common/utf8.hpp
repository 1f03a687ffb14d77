// Text from files for protocols that require UTF-8 (protobuf's proto3
// string fields refuse to parse anything else): a corrupt HDF5 file can hold
// any bytes in an attribute or a link name.
#pragma once

#include <string>
#include <string_view>

namespace crackvis {

// Whether `text` is well-formed UTF-8 (no overlong forms, surrogates or code
// points past U+10FFFF).
bool isValidUtf8(std::string_view text);
// `text` itself when valid; otherwise each byte that does not start a
// well-formed sequence is replaced by U+FFFD.
std::string toValidUtf8(std::string_view text);

}  // namespace crackvis
