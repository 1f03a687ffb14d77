// Reading a pipeline description file for the commands that render one
// (snapshot, movie): one place for the error that names the file.
#pragma once

#include <string>

#include <crackvis/common/status.hpp>
#include <crackvis/pipeline/pipeline_description.hpp>

namespace crackvis::cli {

// The description in `path` (an empty path: the schema's defaults).
// NOT_FOUND for a file that cannot be read, INVALID_ARGUMENT naming the file
// and the line for an invalid one.
Result<pipeline::PipelineDescription> readPipelineFile(const std::string& path);

}  // namespace crackvis::cli
