// libFuzzer target: pipeline descriptions (pipeline/). Any input must
// end in a description or an INVALID_ARGUMENT, never a crash, an exception or
// a sanitizer report; and a description that parses must survive toXml and
// parse back to the same values (the attribute conversions and their
// inverse agree).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string_view>

#include "fuzz_require.hpp"
#include <crackvis/pipeline/pipeline_description.hpp>

const char* const kFuzzTargetName = "pipeline fuzzer";

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace crackvis;
  const std::string_view xml(reinterpret_cast<const char*>(data), size);
  auto parsed = pipeline::parsePipeline(xml);
  if (!parsed) {
    require(parsed.status().code() == StatusCode::kInvalidArgument,
            "a refused document is not INVALID_ARGUMENT");
    require(parsed.status().message().find('\n') == std::string::npos,
            "an error message spans lines");
    return 0;
  }
  auto again = pipeline::parsePipeline(pipeline::toXml(*parsed));
  require(again.isOk(), "toXml of a parsed description does not parse");
  require(*again == *parsed, "toXml and parse disagree");
  return 0;
}
