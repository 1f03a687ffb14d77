// Renders one step of a DEM data set as a pipeline description says, off
// screen (EglContext), into an RGB image: particles as GLSL sphere impostors
// (point sprites that write their depth, hidden ones left out on the CPU:
// src/point_sprite_sphere_mapper.hpp), crack surfaces from any of the four methods, broken
// or all bonds as lines or tubes, inconsistency marks, the local
// decomposition, background, colour map, scalar bar and camera. The building
// block of the render server's sessions and of `crackvis snapshot`.
//
// A session sets a scene once per step or description (setScene) and then
// renders it as often as the camera moves (renderFrame), at full or reduced
// resolution: frames of any size up to the capacity given at creation come
// from the same context.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/cracks/extractor.hpp>
#include <crackvis/pipeline/pipeline_description.hpp>
#include <crackvis/render/camera_move.hpp>
#include <crackvis/scene_model/scene_input.hpp>
#include <crackvis/scene_model/scene_pick.hpp>

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

// Scales `in` up (pixel replication, ParaView's reduced-resolution look) or
// down (nearest pixel) to width x height.
void resample(const Image& in, int width, int height, Image& out);

// What one step needs besides the description (made by a
// scene::ScenePipeline or by hand in tests).
using SceneInput = scene::SceneInput;

class SceneRenderer {
 public:
  // An off-screen context that holds frames up to width x height. setScene
  // and renderFrame make it current on the calling thread first.
  static Result<std::unique_ptr<SceneRenderer>> create(int width, int height);
  ~SceneRenderer();
  // Hands the context over: the thread that created the renderer calls this
  // before another thread uses it.
  void releaseContext();

  // Builds the scene's actors. The camera is kept across calls; it is set
  // from the description's camera (or reset to show everything) on the first
  // call, when `resetCamera` is true, and by moveCamera(kReset).
  Status setScene(const pipeline::PipelineDescription& description, const SceneInput& input,
                  bool resetCamera = false);
  // How much of the scene a frame draws. kCoarse: the particles and the
  // crack surfaces by coarse stand-ins (what lies within two particle
  // diameters of each other clustered into one sphere or one vertex,
  // coarse_geometry.hpp), for a drag's frames while other sessions render
  // at the same time: llvmpipe's frame costs by its primitives, not by its
  // pixels. The stand-ins are made by prepareCoarse or a scene's first
  // coarse frame and kept until the next setScene or setImpostorOptions.
  // Other layers are drawn as they are.
  enum class FrameDetail { kFull, kCoarse };
  // Renders the scene at width x height (at most the capacity).
  Status renderFrame(int width, int height, Image& out, FrameDetail detail = FrameDetail::kFull);
  // Makes the scene's coarse stand-ins now if not yet made, so that a
  // caller can make them outside its render turn (about 6 ms for cuboid A).
  void prepareCoarse();
  // Whether the last frame drew coarse stand-ins: a kCoarse frame of a
  // scene with particles as impostors or crack surfaces to stand in for.
  bool drewStandIns() const;
  // setScene(description, input, true) then renderFrame at the description's
  // view size: a snapshot.
  Status render(const pipeline::PipelineDescription& description, const SceneInput& input,
                Image& out);
  // Draws `input` as `description` says, once, at the description's view
  // size, and forgets it: the camera is as before and the next setScene
  // replaces what it made, as the first one would. What stays is what a first frame otherwise
  // waits for: the window's shader programs (VTK compiles them at an
  // actor's first draw and keeps them per window, by their source) with
  // llvmpipe's code for them, the frame buffers and the read-back buffer.
  Status rehearse(const pipeline::PipelineDescription& description, const SceneInput& input);
  // Drops the scene (its actors, their arrays, the overlays) and resets the
  // camera and the impostor options to a new renderer's, keeping the
  // context, its frame buffers and its compiled shader programs: for a
  // renderer handed on to another user's session. The read-back buffer is
  // zeroed and an empty frame drawn at full size, so neither holds the last
  // picture. An error (no context, VTK's) means the renderer must not be
  // handed on.
  Status clearScene();

  // kRotate: dx, dy drag the scene (trackball); kPan: the scene follows the
  // drag; kZoom: dx > 0 zooms in (factor exp(dx)); kReset: fit the scene.
  void moveCamera(CameraMove move, double dx, double dy);
  pipeline::CameraDescription camera() const;
  void setCamera(const pipeline::CameraDescription& camera);
  // The ray from the eye through (x, y) of a width x height frame, as
  // fractions of it from its top-left corner (a double click), through the
  // scene's viewport (the legend strip beside it is not the scene).
  scene::Ray viewRay(double x, double y, int width, int height);

  // How impostor particles are drawn, for tests and benchmarks: with VTK's
  // geometry shader (vtkOpenGLSphereMapper's way) instead of points, and
  // whether spheres hidden behind others are left out (the picture is the
  // same). Kept across scenes.
  struct ImpostorOptions {
    bool geometryShader = false;
    bool occlusionCulling = true;
    // Spheres from which culling goes by cells kept between frames
    // (SphereCells, sphere_occlusion.hpp).
    std::size_t occlusionCellThreshold = 16384;
  };
  void setImpostorOptions(const ImpostorOptions& options);
  // Whether a renderer culls hidden spheres by default: on for a software
  // rasteriser (llvmpipe), off for a GPU; `setting` is the value of
  // CRACKVIS_OCCLUSION_CULLING (on, off, auto or null), which overrides it.
  static Result<bool> occlusionCullingFor(std::string_view glRenderer, const char* setting);
  // The last frame's impostors (a coarse frame's: the stand-in's): spheres
  // drawn, of how many, and whether as points (false: the geometry shader,
  // also used for a sphere wider than the largest point). All 0 without
  // impostors.
  struct ImpostorStats {
    std::int64_t drawn = 0;
    std::int64_t spheres = 0;
    bool points = false;
  };
  ImpostorStats impostorStats() const;

  int capacityWidth() const;
  int capacityHeight() const;
  // "EGL 1.5 (Mesa Project, surfaceless); OpenGL renderer: llvmpipe ..."
  const std::string& backend() const { return m_backend; }

 private:
  SceneRenderer();
  struct Impl;
  std::unique_ptr<Impl> m_impl;
  std::string m_backend;
};

Status writePng(const Image& image, const std::string& path);
// The PNG file's bytes (for the render service's Snapshot).
Result<std::vector<std::uint8_t>> encodePng(const Image& image);

}  // namespace crackvis::render
