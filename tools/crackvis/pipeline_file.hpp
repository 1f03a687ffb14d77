// What the commands that render (snapshot, movie, bench render) read from
// their options: a pipeline description file, one place for the error that
// names the file, and a frame size.
#pragma once

#include <string>
#include <utility>

#include <crackvis/common/status.hpp>
#include <crackvis/pipeline/pipeline_description.hpp>

namespace crackvis::cli {

// The description in `path` (an empty path: the schema's defaults).
// NOT_FOUND for a file that cannot be read, INVALID_ARGUMENT naming the file
// and the line for an invalid one.
Result<pipeline::PipelineDescription> readPipelineFile(const std::string& path);

// The smallest and largest frame edge a command renders; H.264 (4:2:0)
// needs even sizes.
inline constexpr int kMinFrameEdge = 16;
inline constexpr int kMaxFrameEdge = 7680;

// "WIDTHxHEIGHT" (or "WIDTHXHEIGHT") as given to --size: INVALID_ARGUMENT
// for any other spelling, a number beyond an int, or an edge that is odd or
// outside kMinFrameEdge..kMaxFrameEdge.
Result<std::pair<int, int>> parseFrameSize(const std::string& text);

}  // namespace crackvis::cli
