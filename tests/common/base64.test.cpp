// Standard base64 (crackvis/common/base64.hpp): RFC 4648's test vectors,
// every length round trips, and what is not base64 is refused.
#include <random>
#include <string>
#include <utility>

#include <catch2/catch.hpp>

#include <crackvis/common/base64.hpp>

namespace crackvis::testing {

TEST_CASE("base64 encodes RFC 4648's vectors and decodes what it encodes", "[common]") {
  for (const auto& [plain, encoded] : {std::pair{"f", "Zg=="},
                                       {"fo", "Zm8="},
                                       {"foo", "Zm9v"},
                                       {"foob", "Zm9vYg=="},
                                       {"fooba", "Zm9vYmE="},
                                       {"foobar", "Zm9vYmFy"},
                                       {"bob:pw", "Ym9iOnB3"}}) {
    CHECK(base64Encode(plain) == encoded);
    CHECK(base64Decode(encoded) == std::string(plain));
  }
  CHECK(base64Encode("").empty());
  std::mt19937 random(5);
  for (std::size_t length = 1; length < 200; ++length) {
    std::string bytes(length, '\0');
    for (char& byte : bytes) {
      byte = static_cast<char>(random());
    }
    INFO("length " << length);
    CHECK(base64Decode(base64Encode(bytes)) == bytes);
  }
  for (const char* bad : {"", "Zg=", "Z===", "====", "Zg==Zg==", "Zm9v!A==", "Zm9vYmFy\n"}) {
    INFO(bad);
    CHECK_FALSE(base64Decode(bad).has_value());
  }
}

}  // namespace crackvis::testing
