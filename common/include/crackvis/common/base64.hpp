// Standard base64 with padding (RFC 4648 section 4), through OpenSSL's
// encoder: the one implementation behind Basic credentials, sent by the
// data client and read by the servers, and the stored secret hashes.
#pragma once

#include <optional>
#include <string>
#include <string_view>

namespace crackvis {

std::string base64Encode(std::string_view bytes);
// nullopt for text that is not base64 with padding (empty included).
std::optional<std::string> base64Decode(std::string_view text);

}  // namespace crackvis
