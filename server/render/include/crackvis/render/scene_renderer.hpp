// Renders one step of a DEM data set as a pipeline description says, off
// screen (EglContext), into an RGB image: particles as GLSL sphere impostors
// (vtkOpenGLSphereMapper), crack surfaces from any of the four methods,
// broken or all bonds as lines, inconsistency marks, background, colour map
// and camera. The building block of the render server's sessions and of
// `crackvis snapshot`.
//
// Not yet from the description: bonds as tubes, the decomposition display
// and the scalar bar (the render-server issue's remaining points).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/cracks/extractor.hpp>
#include <crackvis/pipeline/pipeline_description.hpp>

namespace crackvis::render {

struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  // rows top to bottom, 3 bytes per pixel

  const std::uint8_t* pixel(int x, int y) const {
    return rgb.data() + 3 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                             static_cast<std::size_t>(x));
  }
};

// What one step needs besides the description: the lattice, the step, the
// reference positions (step 0, for displacement) and the extracted cracks.
struct SceneInput {
  const dem::Lattice* lattice = nullptr;
  cracks::StepInput step;
  std::span<const dem::Vec3> initialPositions;       // may be empty
  std::span<const std::array<float, 3>> velocities;  // may be empty
  const cracks::CrackMesh* cracks = nullptr;         // may be null
};

class SceneRenderer {
 public:
  // An off-screen context and render window of the description's size.
  static Result<std::unique_ptr<SceneRenderer>> create(int width, int height);
  ~SceneRenderer();

  Status render(const pipeline::PipelineDescription& description, const SceneInput& input,
                Image& out);
  // "EGL 1.5 (Mesa Project, surfaceless); OpenGL renderer: llvmpipe ..."
  const std::string& backend() const { return m_backend; }

 private:
  SceneRenderer();
  struct Impl;
  std::unique_ptr<Impl> m_impl;
  std::string m_backend;
};

Status writePng(const Image& image, const std::string& path);

}  // namespace crackvis::render
