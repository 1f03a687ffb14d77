// SceneRenderer: the off-screen window, building a scene, rendering its
// frames and moving its camera.
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <mutex>
#include <numbers>
#include <optional>
#include <vector>

#include <fmt/format.h>
#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkGenericOpenGLRenderWindow.h>
#include <vtkNew.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkRenderer.h>
#include <vtkUnsignedCharArray.h>

#include "overlays.hpp"
#include "point_sprite_sphere_mapper.hpp"
#include "scene_actors.hpp"
#include "vtk_errors.hpp"
#include <crackvis/render/coarse_geometry.hpp>
#include <crackvis/render/egl_context.hpp>
#include <crackvis/render/scene_renderer.hpp>

namespace crackvis::render {
namespace {

using detail::addBonds;
using detail::addCracks;
using detail::addDecompositionEdges;
using detail::particleActor;

// xmin, xmax, ymin, ymax, zmin, zmax of the particles with their radii;
// empty (min > max) without particles.
std::array<double, 6> specimenBounds(const cracks::StepInput& step) {
  std::array<double, 6> b{0, -1, 0, -1, 0, -1};
  if (step.positions.empty()) {
    return b;
  }
  b = {std::numeric_limits<double>::max(), std::numeric_limits<double>::lowest(),
       std::numeric_limits<double>::max(), std::numeric_limits<double>::lowest(),
       std::numeric_limits<double>::max(), std::numeric_limits<double>::lowest()};
  for (std::size_t i = 0; i < step.positions.size(); ++i) {
    const double r = i < step.radius.size() ? step.radius[i] : 0.0;
    const dem::Vec3& p = step.positions[i];
    b[0] = std::min(b[0], p.x - r);
    b[1] = std::max(b[1], p.x + r);
    b[2] = std::min(b[2], p.y - r);
    b[3] = std::max(b[3], p.y + r);
    b[4] = std::min(b[4], p.z - r);
    b[5] = std::max(b[5], p.z + r);
  }
  return b;
}

// Two mean particle diameters: the coarse stand-ins' cell (eight lattice
// neighbours become one sphere); 0 without particles.
double coarseCell(const cracks::StepInput& step) {
  return step.radius.empty() ? 0.0 : 4.0 * detail::meanRadius(step.radius);
}

// A layer's coarse stand-in (FrameDetail::kCoarse): its actor, the actor's
// own mapper and the stand-in's, swapped in for a coarse frame.
struct StandIn {
  vtkSmartPointer<vtkActor> actor;
  vtkSmartPointer<vtkMapper> own;
  vtkSmartPointer<vtkMapper> coarse;
};

}  // namespace

struct SceneRenderer::Impl {
  std::unique_ptr<EglContext> egl;
  vtkSmartPointer<vtkGenericOpenGLRenderWindow> window;
  vtkSmartPointer<vtkRenderer> renderer;  // kept across scenes: it owns the camera
  int width = 0;                          // capacity
  int height = 0;
  bool cameraSet = false;
  vtkSmartPointer<vtkPointSpriteSphereMapper> impostors;  // null unless particles are impostors
  // The last frame's impostors (the particles' own or their stand-in's),
  // and whether that frame drew stand-ins.
  vtkPointSpriteSphereMapper* drawnImpostors = nullptr;
  bool drewStandIns = false;
  ImpostorOptions impostorOptions;
  // What this renderer's OpenGL calls for (occlusionCullingFor): the options
  // a cleared scene goes back to, so that a kept renderer draws as a new one.
  ImpostorOptions defaultImpostorOptions;
  std::unique_ptr<Overlays> overlays;   // scalar bars and annotations
  vtkNew<vtkUnsignedCharArray> pixels;  // the last frame read back
  // The whole specimen at the step shown (every particle with its radius):
  // what a camera reset fits, whatever is hidden, clipped or thresholded.
  std::array<double, 6> specimenBounds{0, -1, 0, -1, 0, -1};
  // The layers a coarse frame draws by stand-ins (FrameDetail::kCoarse), and
  // the stand-ins, made by prepareCoarse or the scene's first coarse frame.
  vtkSmartPointer<vtkActor> particleActor;  // impostors only; null otherwise
  vtkSmartPointer<vtkActor> crackActor;
  double coarseCell = 0.0;
  std::optional<std::vector<StandIn>> standIns;

  void forgetStandIns() {
    drawnImpostors = nullptr;
    drewStandIns = false;
    particleActor = nullptr;
    crackActor = nullptr;
    standIns.reset();
  }
  const std::vector<StandIn>& coarseStandIns();

  void resetCamera() {
    if (specimenBounds[0] <= specimenBounds[1]) {
      renderer->ResetCamera(specimenBounds.data());
    } else {
      renderer->ResetCamera();
    }
  }

  void applyImpostorOptions() {
    if (impostors) {
      impostors->SetForceGeometryShader(impostorOptions.geometryShader);
      impostors->SetOcclusionCulling(impostorOptions.occlusionCulling);
      impostors->SetOcclusionCellThreshold(impostorOptions.occlusionCellThreshold);
    }
    // The particles' stand-in takes the options when made again.
    standIns.reset();
    drawnImpostors = nullptr;
  }
};

namespace {
// A stand-in's mapper colours and clips as the layer's own. Not
// ShallowCopy: vtkOpenGLPolyDataMapper's copies the shader code through
// calls deprecated in VTK 9, each of which logs a warning.
void copyColouring(vtkMapper& from, vtkMapper& to) {
  to.SetLookupTable(from.GetLookupTable());
  to.SetScalarVisibility(from.GetScalarVisibility());
  to.SetScalarRange(from.GetScalarRange());
  to.SetScalarMode(from.GetScalarMode());
  to.SetColorMode(from.GetColorMode());
  to.SetUseLookupTableScalarRange(from.GetUseLookupTableScalarRange());
  to.SetInterpolateScalarsBeforeMapping(from.GetInterpolateScalarsBeforeMapping());
  if (from.GetArrayAccessMode() == VTK_GET_ARRAY_BY_ID) {
    to.ColorByArrayComponent(from.GetArrayId(), from.GetArrayComponent());
  } else {
    to.ColorByArrayComponent(from.GetArrayName(), from.GetArrayComponent());
  }
  to.SetClippingPlanes(from.GetClippingPlanes());
}

// The stand-ins' mappers on their actors while it lives.
class StandInsSwapped {
 public:
  explicit StandInsSwapped(const std::vector<StandIn>& standIns) : m_standIns(standIns) {
    for (const auto& standIn : m_standIns) {
      standIn.actor->SetMapper(standIn.coarse);
    }
  }
  ~StandInsSwapped() {
    for (const auto& standIn : m_standIns) {
      standIn.actor->SetMapper(standIn.own);
    }
  }
  StandInsSwapped(const StandInsSwapped&) = delete;
  StandInsSwapped& operator=(const StandInsSwapped&) = delete;

 private:
  const std::vector<StandIn>& m_standIns;
};
}  // namespace

// A layer without a stand-in (no clusters, another kind of data) is drawn
// as it is.
const std::vector<StandIn>& SceneRenderer::Impl::coarseStandIns() {
  if (standIns) {
    return *standIns;
  }
  // Made aside and kept whole: an exception partway (out of memory) leaves
  // none, to be tried again at the next coarse frame.
  std::vector<StandIn> made;
  if (particleActor) {
    auto* own = vtkPointSpriteSphereMapper::SafeDownCast(particleActor->GetMapper());
    auto* spheres = own != nullptr ? vtkPolyData::SafeDownCast(own->GetInput()) : nullptr;
    if (auto coarse = spheres != nullptr
                          ? coarseSpheres(*spheres, detail::kSphereRadiusArray, coarseCell)
                          : nullptr) {
      auto mapper = vtkSmartPointer<vtkPointSpriteSphereMapper>::New();
      copyColouring(*own, *mapper);
      mapper->SetScaleArray(detail::kSphereRadiusArray);
      mapper->SetRadius(own->GetRadius());
      mapper->SetForceGeometryShader(impostorOptions.geometryShader);
      mapper->SetOcclusionCulling(impostorOptions.occlusionCulling);
      mapper->SetOcclusionCellThreshold(impostorOptions.occlusionCellThreshold);
      mapper->SetInputData(coarse);
      made.push_back({particleActor, own, mapper});
    }
  }
  if (crackActor) {
    auto* own = vtkPolyDataMapper::SafeDownCast(crackActor->GetMapper());
    auto* surface = own != nullptr ? vtkPolyData::SafeDownCast(own->GetInput()) : nullptr;
    if (auto coarse = surface != nullptr ? coarseSurface(*surface, coarseCell) : nullptr) {
      auto mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
      copyColouring(*own, *mapper);
      mapper->SetInputData(coarse);
      made.push_back({crackActor, own, mapper});
    }
  }
  standIns = std::move(made);
  return *standIns;
}

SceneRenderer::SceneRenderer() : m_impl(std::make_unique<Impl>()) {}
SceneRenderer::~SceneRenderer() {
  if (m_impl && m_impl->egl) {
    (void)m_impl->egl->makeCurrent();
    m_impl->overlays.reset();
    m_impl->renderer = nullptr;
    m_impl->window = nullptr;  // GL resources go while the context is current
  }
}

void SceneRenderer::releaseContext() {
  m_impl->egl->releaseFromThread();
}

int SceneRenderer::capacityWidth() const {
  return m_impl->width;
}
int SceneRenderer::capacityHeight() const {
  return m_impl->height;
}

Result<std::unique_ptr<SceneRenderer>> SceneRenderer::create(int width, int height) {
  if (width < 16 || height < 16 || width > 8192 || height > 8192) {
    return invalidArgument(fmt::format("view size {}x{} outside 16..8192", width, height));
  }
  auto egl = EglContext::create(width, height);
  if (!egl) {
    return egl.status();
  }
  const VtkErrorScope vtkErrors;
  std::unique_ptr<SceneRenderer> renderer(new SceneRenderer());
  Impl& impl = *renderer->m_impl;
  impl.egl = std::move(egl).value();
  impl.width = width;
  impl.height = height;
  impl.window = vtkSmartPointer<vtkGenericOpenGLRenderWindow>::New();
  impl.window->SetSize(width, height);
  impl.window->SetMultiSamples(0);  // about 10x slower on llvmpipe
  impl.window->SetOffScreenRendering(true);
  impl.window->InitializeFromCurrentContext();
  impl.window->SetIsCurrent(true);
  impl.window->SetReadyForRendering(true);
  // One empty frame initializes VTK's OpenGL state on the EGL context; a
  // broken driver shows here rather than in the first session.
  impl.renderer = vtkSmartPointer<vtkRenderer>::New();
  impl.window->AddRenderer(impl.renderer);
  impl.overlays = std::make_unique<Overlays>(impl.window, impl.renderer);
  impl.window->Render();
  CRACKVIS_RETURN_IF_ERROR(
      vtkErrors.status(fmt::format("{}: the first frame", impl.egl->description())));
  const char* capabilities = impl.window->ReportCapabilities();
  if (capabilities == nullptr || std::string(capabilities).find("OpenGL") == std::string::npos) {
    return failedPrecondition(
        fmt::format("{}: VTK could not initialize OpenGL on it", impl.egl->description()));
  }
  std::string glRenderer = "unknown";
  const std::string text = capabilities;
  if (const auto at = text.find("OpenGL renderer string:"); at != std::string::npos) {
    glRenderer = text.substr(at + 24, text.find('\n', at) - at - 24);
  }
  const auto culling = occlusionCullingFor(glRenderer, std::getenv("CRACKVIS_OCCLUSION_CULLING"));
  if (!culling) {
    return culling.status();
  }
  impl.defaultImpostorOptions.occlusionCulling = *culling;
  impl.impostorOptions = impl.defaultImpostorOptions;
  renderer->m_backend = fmt::format("{}; OpenGL renderer: {}; occlusion culling {}",
                                    impl.egl->description(), glRenderer, *culling ? "on" : "off");
  return renderer;
}

Result<bool> SceneRenderer::occlusionCullingFor(std::string_view glRenderer, const char* setting) {
  std::string chosen = setting != nullptr ? setting : "auto";
  std::transform(chosen.begin(), chosen.end(), chosen.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (chosen == "on" || chosen == "off") {
    return chosen == "on";
  }
  if (chosen != "auto" && !chosen.empty()) {
    return invalidArgument(fmt::format(
        "CRACKVIS_OCCLUSION_CULLING is '{}': give on, off or auto (the default)", setting));
  }
  // A software rasteriser shades every fragment on the CPU: finding the
  // hidden spheres first pays (cuboid A's full frame 450 -> 250 ms on
  // llvmpipe, docs/benchmarks.md). A GPU draws them faster than the CPU
  // finds them (docs/benchmarks.md, "A GPU node").
  for (const std::string_view software : {"llvmpipe", "softpipe", "SwiftShader", "Software"}) {
    if (glRenderer.find(software) != std::string_view::npos) {
      return true;
    }
  }
  return false;
}

Status SceneRenderer::setScene(const pipeline::PipelineDescription& d, const SceneInput& input,
                               bool resetCamera) {
  Impl& impl = *m_impl;
  if (input.lattice == nullptr) {
    return invalidArgument("a scene needs the lattice");
  }
  CRACKVIS_RETURN_IF_ERROR(impl.egl->makeCurrent());
  const VtkErrorScope vtkErrors;
  vtkRenderer* renderer = impl.renderer;
  renderer->RemoveAllViewProps();
  renderer->SetBackground(d.view.background.r / 255.0, d.view.background.g / 255.0,
                          d.view.background.b / 255.0);
  std::vector<Legend> legends;
  impl.impostors = nullptr;
  impl.forgetStandIns();
  impl.coarseCell = coarseCell(input.step);
  if (d.particles.visible) {
    auto particles = particleActor(d, input, &legends);
    renderer->AddActor(particles);
    impl.impostors = vtkPointSpriteSphereMapper::SafeDownCast(particles->GetMapper());
    impl.applyImpostorOptions();
    if (impl.impostors) {
      impl.particleActor = particles;
    }
  }
  if (d.cracks.visible && input.cracks != nullptr) {
    impl.crackActor = addCracks(d, input, renderer, &legends);
  }
  if (d.showDecomposition && input.decomposition != nullptr) {
    addDecompositionEdges(input, renderer);
  }
  if (d.bonds.show != pipeline::BondSelection::kNone) {
    addBonds(d, input, renderer, &legends);
  }
  // Before the camera: the legend strip narrows the scene's viewport.
  impl.overlays->setScene(d, input, std::move(legends));
  impl.specimenBounds = specimenBounds(input.step);
  if (resetCamera || !impl.cameraSet) {
    if (d.view.camera) {
      setCamera(*d.view.camera);
    } else {
      impl.resetCamera();
    }
    impl.cameraSet = true;
  }
  renderer->ResetCameraClippingRange();
  return vtkErrors.status("building the scene");
}

Status SceneRenderer::renderFrame(int width, int height, Image& out, FrameDetail detail) {
  Impl& impl = *m_impl;
  if (width < 1 || height < 1 || width > impl.width || height > impl.height) {
    return invalidArgument(fmt::format("frame {}x{} does not fit the renderer's {}x{}", width,
                                       height, impl.width, impl.height));
  }
  CRACKVIS_RETURN_IF_ERROR(impl.egl->makeCurrent());
  const VtkErrorScope vtkErrors;
  // A frame smaller than the pbuffer renders into its lower-left corner.
  impl.window->SetSize(width, height);
  impl.overlays->layout(width, height);
  const std::vector<StandIn> noStandIns;
  const auto& standIns = detail == FrameDetail::kCoarse ? impl.coarseStandIns() : noStandIns;
  {
    // The layers' own mappers come back however the frame ends.
    const StandInsSwapped swapped(standIns);
    impl.renderer->ResetCameraClippingRange();
    std::unique_lock<std::mutex> text(Overlays::textMutex(), std::defer_lock);
    if (impl.overlays->drawsText()) {
      text.lock();
    }
    impl.window->Render();
  }
  impl.drewStandIns = !standIns.empty();
  impl.drawnImpostors = impl.impostors;
  for (const auto& standIn : standIns) {
    if (standIn.actor == impl.particleActor) {
      impl.drawnImpostors = vtkPointSpriteSphereMapper::SafeDownCast(standIn.coarse);
    }
  }
  CRACKVIS_RETURN_IF_ERROR(vtkErrors.status(fmt::format("rendering a {}x{} frame", width, height)));
  // The read-back buffer is the renderer's, kept from frame to frame (a
  // 720p frame's 2.7 MB, fresh each frame, cost page faults every frame).
  vtkUnsignedCharArray* pixels = impl.pixels;
  const std::size_t row = static_cast<std::size_t>(width) * 3;
  if (impl.window->GetPixelData(0, 0, width - 1, height - 1, 0, pixels, 0) != VTK_OK ||
      static_cast<std::size_t>(pixels->GetNumberOfValues()) !=
          row * static_cast<std::size_t>(height)) {
    return internalError(fmt::format("reading the {}x{} frame's pixels back from GL failed ({})",
                                     width, height, vtkErrors.status("glReadPixels").message()));
  }
  out.width = width;
  out.height = height;
  // Capacity beyond the pixels: swscale reads RGB rows in whole SIMD blocks.
  // The rows are appended, not written over zeros: a frame is never cleared
  // first.
  out.rgb.clear();
  out.rgb.reserve(row * static_cast<std::size_t>(height) + 256);
  // OpenGL's rows run bottom to top.
  for (int y = height - 1; y >= 0; --y) {
    const std::uint8_t* first = pixels->GetPointer(0) + static_cast<std::size_t>(y) * row;
    out.rgb.insert(out.rgb.end(), first, first + row);
  }
  return Status::ok();
}

Status SceneRenderer::render(const pipeline::PipelineDescription& d, const SceneInput& input,
                             Image& out) {
  CRACKVIS_RETURN_IF_ERROR(setScene(d, input, true));
  return renderFrame(d.view.width, d.view.height, out);
}

Status SceneRenderer::rehearse(const pipeline::PipelineDescription& d, const SceneInput& input) {
  Impl& impl = *m_impl;
  CRACKVIS_RETURN_IF_ERROR(impl.egl->makeCurrent());
  vtkNew<vtkCamera> camera;
  camera->DeepCopy(impl.renderer->GetActiveCamera());
  const bool cameraSet = impl.cameraSet;
  Image frame;
  Status drawn = setScene(d, input, true);
  if (drawn) {
    drawn = renderFrame(d.view.width, d.view.height, frame);
  }
  const ImpostorOptions options = impl.impostorOptions;
  const Status cleared = clearScene();
  impl.impostorOptions = options;
  impl.renderer->GetActiveCamera()->DeepCopy(camera);
  impl.cameraSet = cameraSet;
  return drawn ? cleared : drawn;
}

Status SceneRenderer::clearScene() {
  Impl& impl = *m_impl;
  CRACKVIS_RETURN_IF_ERROR(impl.egl->makeCurrent());
  const VtkErrorScope vtkErrors;
  impl.renderer->RemoveAllViewProps();
  impl.impostors = nullptr;
  impl.forgetStandIns();
  impl.impostorOptions = impl.defaultImpostorOptions;
  pipeline::PipelineDescription empty;
  empty.view.width = impl.width;
  empty.view.height = impl.height;
  empty.view.scalarBar = false;
  empty.annotations.show = false;
  impl.overlays->setScene(empty, SceneInput{}, {});
  vtkNew<vtkCamera> fresh;
  impl.renderer->GetActiveCamera()->DeepCopy(fresh);
  impl.cameraSet = false;
  impl.specimenBounds = {0, -1, 0, -1, 0, -1};
  // The last frame read back is overwritten, not freed: its pages stay
  // mapped for the next frame.
  std::fill_n(impl.pixels->GetPointer(0), impl.pixels->GetNumberOfValues(), std::uint8_t{0});
  // An empty frame at full size, as a new renderer's: the frame buffers hold
  // the background only, and llvmpipe lets go of the last scene's binned
  // geometry. A window left inside a Render (an exception through one) no
  // longer draws at all: such a renderer is refused.
  if (impl.window->CheckInRenderStatus()) {
    return internalError("the renderer was left inside a frame");
  }
  impl.window->SetSize(impl.width, impl.height);
  impl.window->Render();
  return vtkErrors.status("clearing the scene");
}

void SceneRenderer::prepareCoarse() {
  (void)m_impl->coarseStandIns();
}

bool SceneRenderer::drewStandIns() const {
  return m_impl->drewStandIns;
}

void SceneRenderer::setImpostorOptions(const ImpostorOptions& options) {
  m_impl->impostorOptions = options;
  m_impl->applyImpostorOptions();
}

SceneRenderer::ImpostorStats SceneRenderer::impostorStats() const {
  const vtkPointSpriteSphereMapper* mapper =
      m_impl->drawnImpostors != nullptr ? m_impl->drawnImpostors : m_impl->impostors.Get();
  if (mapper == nullptr) {
    return {};
  }
  return {mapper->GetLastDrawnCount(), mapper->GetLastSphereCount(), mapper->GetLastDrewPoints()};
}

void SceneRenderer::moveCamera(CameraMove move, double dx, double dy) {
  vtkRenderer* renderer = m_impl->renderer;
  vtkCamera* camera = renderer->GetActiveCamera();
  switch (move) {
    case CameraMove::kRotate:
      // VTK's trackball style turns 200 degrees per window of drag.
      camera->Azimuth(-200.0 * dx);
      camera->Elevation(200.0 * dy);
      camera->OrthogonalizeViewUp();
      break;
    case CameraMove::kPan: {
      double position[3];
      double focal[3];
      double up[3];
      double direction[3];
      camera->GetPosition(position);
      camera->GetFocalPoint(focal);
      camera->GetViewUp(up);
      camera->GetDirectionOfProjection(direction);
      const double right[3] = {direction[1] * up[2] - direction[2] * up[1],
                               direction[2] * up[0] - direction[0] * up[2],
                               direction[0] * up[1] - direction[1] * up[0]};
      // The view's extent at the focal point, so the scene follows the mouse.
      const double height =
          2.0 * camera->GetDistance() * std::tan(camera->GetViewAngle() * std::numbers::pi / 360.0);
      // The scene's viewport (the legend strip beside it is not the scene).
      const double aspect = m_impl->renderer->GetTiledAspectRatio();
      const double sx = -dx * height * aspect;
      const double sy = dy * height;
      for (int k = 0; k < 3; ++k) {
        const double shift = sx * right[k] + sy * up[k];
        position[k] += shift;
        focal[k] += shift;
      }
      camera->SetPosition(position);
      camera->SetFocalPoint(focal);
      break;
    }
    case CameraMove::kZoom:
      camera->Dolly(std::exp(dx));
      break;
    case CameraMove::kReset:
      m_impl->resetCamera();
      break;
  }
  renderer->ResetCameraClippingRange();
}

pipeline::CameraDescription SceneRenderer::camera() const {
  vtkCamera* camera = m_impl->renderer->GetActiveCamera();
  pipeline::CameraDescription c;
  double v[3];
  camera->GetPosition(v);
  c.position = {v[0], v[1], v[2]};
  camera->GetFocalPoint(v);
  c.focalPoint = {v[0], v[1], v[2]};
  camera->GetViewUp(v);
  c.viewUp = {v[0], v[1], v[2]};
  c.viewAngle = camera->GetViewAngle();
  return c;
}

scene::Ray SceneRenderer::viewRay(double x, double y, int width, int height) {
  Impl& impl = *m_impl;
  width = std::clamp(width, 1, impl.width);
  height = std::clamp(height, 1, impl.height);
  // The frame's layout, as renderFrame makes it, decides the scene's viewport.
  impl.window->SetSize(width, height);
  impl.overlays->layout(width, height);
  vtkRenderer* renderer = impl.renderer;
  const double px = x * width;
  const double py = (1.0 - y) * height;  // VTK's display origin is bottom-left
  double ends[2][4];
  for (int k = 0; k < 2; ++k) {
    renderer->SetDisplayPoint(px, py, k == 0 ? 0.0 : 1.0);
    renderer->DisplayToWorld();
    renderer->GetWorldPoint(ends[k]);
    for (int axis = 0; axis < 3; ++axis) {
      ends[k][axis] /= ends[k][3] != 0.0 ? ends[k][3] : 1.0;
    }
  }
  const dem::Vec3 near{ends[0][0], ends[0][1], ends[0][2]};
  const dem::Vec3 far{ends[1][0], ends[1][1], ends[1][2]};
  return {near, far - near};
}

void SceneRenderer::setCamera(const pipeline::CameraDescription& c) {
  vtkCamera* camera = m_impl->renderer->GetActiveCamera();
  camera->SetPosition(c.position.x, c.position.y, c.position.z);
  camera->SetFocalPoint(c.focalPoint.x, c.focalPoint.y, c.focalPoint.z);
  camera->SetViewUp(c.viewUp.x, c.viewUp.y, c.viewUp.z);
  camera->SetViewAngle(c.viewAngle);
  m_impl->renderer->ResetCameraClippingRange();
  m_impl->cameraSet = true;
}

}  // namespace crackvis::render
