#include "pipeline_file.hpp"

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

}  // namespace crackvis::cli
