// UTF-8 checks for text that travels in proto3 strings: what a corrupt file
// may hold in a name becomes U+FFFD, and valid text is left alone.
#include <catch2/catch.hpp>

#include <crackvis/common/utf8.hpp>

namespace crackvis {
namespace {

const std::string kReplacement = "\xEF\xBF\xBD";

TEST_CASE("Valid UTF-8 is kept as it is", "[common]") {
  for (const std::string& text : {std::string(), std::string("positions"),
                                  std::string("r\xC3\xA4umlich \xE2\x82\xAC \xF0\x9F\x98\x80"),
                                  std::string("\xF4\x8F\xBF\xBF"), std::string("a\0b", 3)}) {
    INFO(text);
    CHECK(isValidUtf8(text));
    CHECK(toValidUtf8(text) == text);
  }
}

TEST_CASE("Each byte that starts no well-formed sequence becomes U+FFFD", "[common]") {
  struct Case {
    std::string in;
    std::string out;
  };
  const Case cases[] = {
      {"\xFF", kReplacement},
      {"a\x80z", "a" + kReplacement + "z"},
      {"\xC0\xAF", kReplacement + kReplacement},                     // overlong '/'
      {"\xED\xA0\x80", kReplacement + kReplacement + kReplacement},  // a surrogate
      {"\xF4\x90\x80\x80",
       kReplacement + kReplacement + kReplacement + kReplacement},  // > U+10FFFF
      {"\xE2\x82", kReplacement + kReplacement},                    // cut short
      {"ok\xC3\xA4\xC3", "ok\xC3\xA4" + kReplacement},
  };
  for (const Case& c : cases) {
    INFO(c.in);
    CHECK_FALSE(isValidUtf8(c.in));
    CHECK(toValidUtf8(c.in) == c.out);
    CHECK(isValidUtf8(toValidUtf8(c.in)));
  }
}

}  // namespace
}  // namespace crackvis
