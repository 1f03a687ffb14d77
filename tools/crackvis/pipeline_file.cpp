#include "pipeline_file.hpp"

#include <charconv>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

namespace crackvis::cli {

Result<pipeline::PipelineDescription> readPipelineFile(const std::string& path) {
  if (path.empty()) {
    return pipeline::PipelineDescription{};
  }
  std::ifstream in(path);
  if (!in) {
    return notFound(fmt::format("{}: cannot read the pipeline description", path));
  }
  std::stringstream text;
  text << in.rdbuf();
  auto parsed = pipeline::parsePipeline(text.str());
  if (!parsed) {
    return Status(parsed.status().code(), fmt::format("{}: {}", path, parsed.status().message()));
  }
  return parsed;
}

Result<std::pair<int, int>> parseFrameSize(const std::string& text) {
  const char* const end = text.data() + text.size();
  int width = 0;
  int height = 0;
  auto [afterWidth, widthError] = std::from_chars(text.data(), end, width);
  const bool separated =
      widthError == std::errc() && afterWidth != end && (*afterWidth == 'x' || *afterWidth == 'X');
  auto [afterHeight, heightError] = separated ? std::from_chars(afterWidth + 1, end, height)
                                              : std::from_chars_result{end, widthError};
  if (!separated || heightError != std::errc() || afterHeight != end) {
    const bool tooLarge = widthError == std::errc::result_out_of_range ||
                          heightError == std::errc::result_out_of_range;
    return invalidArgument(fmt::format(
        "--size '{}': {}", echoed(text),
        tooLarge ? "a number beyond any frame size" : "expected WIDTHxHEIGHT, e.g. 1920x1080"));
  }
  if (width < kMinFrameEdge || height < kMinFrameEdge || width > kMaxFrameEdge ||
      height > kMaxFrameEdge || width % 2 != 0 || height % 2 != 0) {
    return invalidArgument(
        fmt::format("--size {}x{}: H.264 (4:2:0) needs even sizes from {} to {} pixels", width,
                    height, kMinFrameEdge, kMaxFrameEdge));
  }
  return std::pair{width, height};
}

}  // namespace crackvis::cli
