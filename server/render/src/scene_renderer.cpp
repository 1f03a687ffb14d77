#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <optional>

#include <crackvis_vtk_conversion.h>
#include <fmt/format.h>
#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDataSetMapper.h>
#include <vtkDoubleArray.h>
#include <vtkFloatArray.h>
#include <vtkGenericOpenGLRenderWindow.h>
#include <vtkImageData.h>
#include <vtkLookupTable.h>
#include <vtkNew.h>
#include <vtkPNGWriter.h>
#include <vtkPlane.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderer.h>
#include <vtkRendererCollection.h>
#include <vtkScalarBarActor.h>
#include <vtkTextProperty.h>
#include <vtkTubeFilter.h>
#include <vtkUnsignedCharArray.h>
#include <vtkUnstructuredGrid.h>

#include "overlays.hpp"
#include "point_sprite_sphere_mapper.hpp"
#include "vtk_errors.hpp"
#include <crackvis/common/pending_file.hpp>
#include <crackvis/render/egl_context.hpp>
#include <crackvis/render/scene_renderer.hpp>
#include <crackvis/scene/scene_content.hpp>

namespace crackvis::render {
namespace {

using pipeline::Colour;
using pipeline::ColourMap;

void setColour(vtkProperty* property, Colour c) {
  property->SetColor(c.r / 255.0, c.g / 255.0, c.b / 255.0);
}

// A lookup table through a few control points of each colour map.
vtkSmartPointer<vtkLookupTable> lookupTable(ColourMap map, double lo, double hi) {
  static const std::vector<std::array<double, 3>> kViridis{{0.267, 0.005, 0.329},
                                                           {0.229, 0.322, 0.546},
                                                           {0.128, 0.567, 0.551},
                                                           {0.369, 0.789, 0.383},
                                                           {0.993, 0.906, 0.144}};
  static const std::vector<std::array<double, 3>> kCoolWarm{
      {0.230, 0.299, 0.754}, {0.865, 0.865, 0.865}, {0.706, 0.016, 0.150}};
  static const std::vector<std::array<double, 3>> kRainbow{
      {0, 0, 1}, {0, 1, 1}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}};
  static const std::vector<std::array<double, 3>> kGray{{0.1, 0.1, 0.1}, {0.95, 0.95, 0.95}};
  const auto& points = map == ColourMap::kCoolWarm    ? kCoolWarm
                       : map == ColourMap::kRainbow   ? kRainbow
                       : map == ColourMap::kGrayscale ? kGray
                                                      : kViridis;
  auto table = vtkSmartPointer<vtkLookupTable>::New();
  constexpr int kColours = 256;
  table->SetNumberOfTableValues(kColours);
  for (int k = 0; k < kColours; ++k) {
    const double t =
        static_cast<double>(k) / (kColours - 1) * static_cast<double>(points.size() - 1);
    const auto i = std::min(static_cast<std::size_t>(t), points.size() - 2);
    const double f = t - static_cast<double>(i);
    table->SetTableValue(k, points[i][0] * (1 - f) + points[i + 1][0] * f,
                         points[i][1] * (1 - f) + points[i + 1][1] * f,
                         points[i][2] * (1 - f) + points[i + 1][2] * f, 1.0);
  }
  table->SetRange(lo, hi > lo ? hi : lo + 1.0);
  table->Build();
  return table;
}

// The range of an array's values (the first component).
scene::ValueRange rangeOf(vtkDataArray* scalars) {
  double range[2] = {0.0, 0.0};
  if (scalars != nullptr && scalars->GetNumberOfTuples() > 0) {
    scalars->GetRange(range);
  }
  return {range[0], range[1]};
}

// Colours `mapper` by `scalars` over `range` and adds the layer's legend.
void colourByScalars(vtkMapper* mapper, vtkDataArray* scalars, bool cellData, ColourMap map,
                     scene::ValueRange range, scene::Quantity quantity,
                     std::vector<Legend>* legends) {
  auto table = lookupTable(map, range.min, range.max);
  mapper->SetLookupTable(table);
  if (legends != nullptr) {
    legends->push_back(Legend{table, std::move(quantity), range});
  }
  mapper->SetScalarRange(range.min, range.max);
  mapper->SetScalarModeToUsePointFieldData();
  if (cellData) {
    mapper->SetScalarModeToUseCellFieldData();
  }
  mapper->SelectColorArray(scalars->GetName());
  mapper->ScalarVisibilityOn();
}

// A layer's clip plane: hides the side its normal points to.
void addClip(vtkMapper* mapper, const std::optional<pipeline::ClipPlane>& clip) {
  if (!clip) {
    return;
  }
  vtkNew<vtkPlane> plane;
  plane->SetOrigin(clip->origin.x, clip->origin.y, clip->origin.z);
  // VTK keeps the side the normal points to; the description hides it.
  plane->SetNormal(-clip->normal.x, -clip->normal.y, -clip->normal.z);
  mapper->AddClippingPlane(plane);
}

vtkSmartPointer<vtkPoints> positionPoints(std::span<const dem::Vec3> positions) {
  auto points = vtkSmartPointer<vtkPoints>::New();
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(static_cast<vtkIdType>(positions.size()));
  std::memcpy(vtkDoubleArray::SafeDownCast(points->GetData())->GetPointer(0), positions.data(),
              positions.size() * sizeof(dem::Vec3));
  return points;
}

const char* particleArrayName(pipeline::ParticleColourBy by) {
  switch (by) {
    case pipeline::ParticleColourBy::kRadius:
      return "radius";
    case pipeline::ParticleColourBy::kDisplacement:
      return "displacement";
    case pipeline::ParticleColourBy::kVelocity:
      return "velocity";
    case pipeline::ParticleColourBy::kDamage:
      return "damage";
    case pipeline::ParticleColourBy::kExtra:
      return "extra";
    case pipeline::ParticleColourBy::kSolid:
      break;
  }
  return "value";
}

const char* bondArrayName(pipeline::BondColourBy by) {
  switch (by) {
    case pipeline::BondColourBy::kForce:
      return "bond_force";
    case pipeline::BondColourBy::kBreakStep:
      return "break_step";
    case pipeline::BondColourBy::kExtra:  // named by the caller
    case pipeline::BondColourBy::kState:
    case pipeline::BondColourBy::kSolid:
      break;
  }
  return "bond_state";
}

vtkSmartPointer<vtkActor> particleActor(const pipeline::PipelineDescription& d,
                                        const SceneInput& input, std::vector<Legend>* legends) {
  const auto& particles = d.particles;
  const std::vector<dem::ParticleIndex> visible = scene::visibleParticles(particles, input);
  const auto n = static_cast<vtkIdType>(visible.size());
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(n);
  for (vtkIdType k = 0; k < n; ++k) {
    const dem::Vec3& p = input.step.positions[static_cast<std::size_t>(visible[k])];
    points->SetPoint(k, p.x, p.y, p.z);
  }
  auto data = vtkSmartPointer<vtkPolyData>::New();
  data->SetPoints(points);
  // The impostor mapper draws vertex cells: one per particle.
  vtkNew<vtkCellArray> vertices;
  for (vtkIdType i = 0; i < n; ++i) {
    vertices->InsertNextCell(1, &i);
  }
  data->SetVerts(vertices);
  vtkNew<vtkFloatArray> radius;
  radius->SetName("sphere_radius");
  radius->SetNumberOfValues(n);
  for (vtkIdType k = 0; k < n; ++k) {
    radius->SetValue(k,
                     static_cast<float>(input.step.radius[static_cast<std::size_t>(visible[k])]));
  }
  data->GetPointData()->AddArray(radius);
  vtkNew<vtkDoubleArray> values;
  // The array's name in the scene: an extra array's own.
  values->SetName(particles.colourBy == pipeline::ParticleColourBy::kExtra
                      ? particles.colourByExtra.c_str()
                      : particleArrayName(particles.colourBy));
  const auto perParticle = scene::particleValues(particles, input);
  values->SetNumberOfValues(n);
  for (vtkIdType k = 0; k < n; ++k) {
    values->SetValue(k, perParticle[static_cast<std::size_t>(visible[k])]);
  }
  data->GetPointData()->AddArray(values);
  // The colour range of all particles, hidden ones included, so that it
  // does not change with what is culled.
  scene::ValueRange valueRange;
  if (!perParticle.empty()) {
    const auto [lo, hi] = std::minmax_element(perParticle.begin(), perParticle.end());
    valueRange = {*lo, *hi};
  }

  vtkSmartPointer<vtkPolyDataMapper> mapper;
  if (particles.representation == pipeline::ParticleRepresentation::kImpostors) {
    // Point sprites, hidden spheres left out (point_sprite_sphere_mapper.hpp).
    auto spheres = vtkSmartPointer<vtkPointSpriteSphereMapper>::New();
    spheres->SetScaleArray("sphere_radius");
    mapper = spheres;
  } else {
    mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
  }
  mapper->SetInputData(data);
  mapper->ScalarVisibilityOff();
  if (particles.colourBy != pipeline::ParticleColourBy::kSolid) {
    colourByScalars(mapper, values, false, d.view.colourMap,
                    scene::colourRange(particles.range, input.series.particles, valueRange),
                    scene::particleQuantity(particles), legends);
  }
  addClip(mapper, particles.clip);
  auto actor = vtkSmartPointer<vtkActor>::New();
  actor->SetMapper(mapper);
  setColour(actor->GetProperty(), particles.colour);
  actor->GetProperty()->SetOpacity(particles.opacity);
  if (particles.representation == pipeline::ParticleRepresentation::kPoints) {
    actor->GetProperty()->SetPointSize(3);
  }
  return actor;
}

// One actor of crack primitives: surfaces (or lines in 2D) through an
// ordinary mapper; volume cells (cell attribute, 3D) through a data set mapper.
// The layer's colour range (`range`, `series`) and legend apply when
// `colourArray` is given.
struct MeshColouring {
  const char* array = nullptr;
  ColourMap map = ColourMap::kViridis;
  pipeline::ColourRange range;
  std::optional<scene::ValueRange> series;
  scene::Quantity quantity;
};

vtkSmartPointer<vtkActor> meshActor(const cracks::CrackMesh& mesh, const MeshColouring& colouring,
                                    std::vector<Legend>* legends) {
  vtkSmartPointer<vtkDataSet> data;
  vtkSmartPointer<vtkMapper> mapper;
  if (mesh.hasVolumeCells()) {
    auto grid = vtkSmartPointer<vtkUnstructuredGrid>::New();
    cracks::vtkadapter::toUnstructuredGrid(mesh, grid);
    auto gridMapper = vtkSmartPointer<vtkDataSetMapper>::New();
    gridMapper->SetInputData(grid);
    data = grid;
    mapper = gridMapper;
  } else {
    auto poly = vtkSmartPointer<vtkPolyData>::New();
    cracks::vtkadapter::toPolyData(mesh, poly);
    auto polyMapper = vtkSmartPointer<vtkPolyDataMapper>::New();
    polyMapper->SetInputData(poly);
    data = poly;
    mapper = polyMapper;
  }
  mapper->ScalarVisibilityOff();
  if (colouring.array != nullptr) {
    const auto colour = [&](vtkDataArray* scalars, bool cellData) {
      colourByScalars(mapper, scalars, cellData, colouring.map,
                      scene::colourRange(colouring.range, colouring.series, rangeOf(scalars)),
                      colouring.quantity, legends);
    };
    if (vtkDataArray* cells = data->GetCellData()->GetArray(colouring.array)) {
      colour(cells, true);
    } else if (vtkDataArray* points = data->GetPointData()->GetArray(colouring.array)) {
      colour(points, false);
    }
  }
  auto actor = vtkSmartPointer<vtkActor>::New();
  actor->SetMapper(mapper);
  actor->GetProperty()->SetLineWidth(2.0);
  actor->GetProperty()->SetPointSize(4.0);
  actor->GetProperty()->BackfaceCullingOff();
  return actor;
}

// Crack primitives of broken, consistent bonds; the local Voronoi
// inconsistency marks (lines between the particle centres) and intact faces
// (the local decomposition) as separate actors when the description shows them.
void addCracks(const pipeline::PipelineDescription& d, const SceneInput& input,
               vtkRenderer* renderer, std::vector<Legend>* legends) {
  const scene::CrackLayers layers = scene::crackLayers(d, *input.cracks);
  const MeshColouring colouring{scene::crackArrayName(d.cracks.colourBy, d.cracks.method),
                                d.view.colourMap, d.cracks.range, input.series.cracks,
                                scene::crackQuantity(d.cracks.colourBy, d.cracks.method)};
  auto actor = meshActor(layers.cracks, colouring, legends);
  addClip(actor->GetMapper(), d.cracks.clip);
  setColour(actor->GetProperty(), d.cracks.colour);
  actor->GetProperty()->SetOpacity(d.cracks.opacity);
  renderer->AddActor(actor);
  if (layers.marks.primitiveCount() > 0) {
    auto marksActor = meshActor(layers.marks, {}, nullptr);
    addClip(marksActor->GetMapper(), d.cracks.clip);
    marksActor->GetProperty()->SetColor(1.0, 0.85, 0.0);  // yellow: stands out on every map
    marksActor->GetProperty()->SetLineWidth(3.0);
    renderer->AddActor(marksActor);
  }
  if (layers.intact.primitiveCount() > 0) {
    auto intactActor = meshActor(layers.intact, {}, nullptr);
    addClip(intactActor->GetMapper(), d.cracks.clip);
    intactActor->GetProperty()->SetColor(0.75, 0.8, 0.9);
    intactActor->GetProperty()->SetOpacity(0.25);
    renderer->AddActor(intactActor);
  }
}

// Lines between the particles of `bonds`, indices into `pairs`.
vtkSmartPointer<vtkPolyData> bondPolyData(const SceneInput& input,
                                          std::span<const dem::BondIndex> bonds,
                                          std::span<const dem::Bond> pairs) {
  vtkNew<vtkCellArray> lines;
  for (dem::BondIndex b : bonds) {
    const dem::Bond& bond = pairs[static_cast<std::size_t>(b)];
    const vtkIdType ids[2] = {bond.first, bond.second};
    lines->InsertNextCell(2, ids);
  }
  auto data = vtkSmartPointer<vtkPolyData>::New();
  data->SetPoints(positionPoints(input.step.positions));
  data->SetLines(lines);
  return data;
}

// The cell methods' local decomposition: the edges of its cells, faint.
void addDecompositionEdges(const SceneInput& input, vtkRenderer* renderer) {
  // The decomposition's graph: on a triangulated packing its edges include
  // pairs that are no bond of the file.
  const auto data =
      bondPolyData(input, scene::decompositionBonds(input), input.decomposition->graph().bonds());
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputData(data);
  mapper->ScalarVisibilityOff();
  vtkNew<vtkActor> actor;
  actor->SetMapper(mapper);
  actor->GetProperty()->SetColor(0.75, 0.8, 0.9);
  actor->GetProperty()->SetOpacity(0.3);
  renderer->AddActor(actor);
}

double meanRadius(std::span<const double> radius) {
  double sum = 0.0;
  for (double r : radius) {
    sum += r;
  }
  return radius.empty() ? 1.0 : sum / static_cast<double>(radius.size());
}

void addBonds(const pipeline::PipelineDescription& d, const SceneInput& input,
              vtkRenderer* renderer, std::vector<Legend>* legends) {
  const scene::BondLines shown = scene::bondLines(d.bonds, input);
  vtkNew<vtkDoubleArray> values;
  values->SetName(d.bonds.colourBy == pipeline::BondColourBy::kExtra
                      ? d.bonds.colourByExtra.c_str()
                      : bondArrayName(d.bonds.colourBy));
  values->SetNumberOfValues(static_cast<vtkIdType>(shown.values.size()));
  std::copy(shown.values.begin(), shown.values.end(), values->GetPointer(0));
  const auto data = bondPolyData(input, shown.bonds, input.lattice->bonds);
  data->GetCellData()->AddArray(values);
  vtkNew<vtkPolyDataMapper> mapper;
  if (d.bonds.representation == pipeline::BondRepresentation::kTubes) {
    vtkNew<vtkTubeFilter> tubes;
    tubes->SetInputData(data);
    tubes->SetRadius(d.bonds.tubeRadius * meanRadius(input.step.radius));
    tubes->SetNumberOfSides(8);
    tubes->CappingOff();
    tubes->Update();
    mapper->SetInputData(tubes->GetOutput());
  } else {
    mapper->SetInputData(data);
  }
  mapper->ScalarVisibilityOff();
  if (d.bonds.colourBy != pipeline::BondColourBy::kSolid) {
    colourByScalars(mapper, values, true, d.view.colourMap,
                    scene::colourRange(d.bonds.range, input.series.bonds, rangeOf(values)),
                    scene::bondQuantity(d.bonds), legends);
  }
  addClip(mapper, d.bonds.clip);
  vtkNew<vtkActor> actor;
  actor->SetMapper(mapper);
  setColour(actor->GetProperty(), d.bonds.colour);
  actor->GetProperty()->SetLineWidth(2.0);
  renderer->AddActor(actor);
}

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

}  // namespace

struct SceneRenderer::Impl {
  std::unique_ptr<EglContext> egl;
  vtkSmartPointer<vtkGenericOpenGLRenderWindow> window;
  vtkSmartPointer<vtkRenderer> renderer;  // kept across scenes: it owns the camera
  int width = 0;                          // capacity
  int height = 0;
  bool cameraSet = false;
  vtkSmartPointer<vtkPointSpriteSphereMapper> impostors;  // null unless particles are impostors
  ImpostorOptions impostorOptions;
  std::unique_ptr<Overlays> overlays;  // scalar bars and annotations
  // The whole specimen at the step shown (every particle with its radius):
  // what a camera reset fits, whatever is hidden, clipped or thresholded.
  std::array<double, 6> specimenBounds{0, -1, 0, -1, 0, -1};

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
  }
};

SceneRenderer::SceneRenderer() : m_impl(std::make_unique<Impl>()) {}
SceneRenderer::~SceneRenderer() {
  if (m_impl && m_impl->egl) {
    (void)m_impl->egl->makeCurrent();
    m_impl->overlays.reset();
    m_impl->renderer = nullptr;
    m_impl->window = nullptr;  // GL resources go while the context is current
  }
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
  renderer->m_backend = fmt::format("{}; OpenGL renderer: {}", impl.egl->description(), glRenderer);
  return renderer;
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
  if (d.particles.visible) {
    auto particles = particleActor(d, input, &legends);
    renderer->AddActor(particles);
    impl.impostors = vtkPointSpriteSphereMapper::SafeDownCast(particles->GetMapper());
    impl.applyImpostorOptions();
  }
  if (d.cracks.visible && input.cracks != nullptr) {
    addCracks(d, input, renderer, &legends);
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

Status SceneRenderer::renderFrame(int width, int height, Image& out,
                                  [[maybe_unused]] bool interactive) {
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
  impl.renderer->ResetCameraClippingRange();
  {
    std::unique_lock<std::mutex> text(Overlays::textMutex(), std::defer_lock);
    if (impl.overlays->drawsText()) {
      text.lock();
    }
    impl.window->Render();
  }
  CRACKVIS_RETURN_IF_ERROR(vtkErrors.status(fmt::format("rendering a {}x{} frame", width, height)));
  vtkNew<vtkUnsignedCharArray> pixels;
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
  out.rgb.reserve(row * static_cast<std::size_t>(height) + 256);
  out.rgb.resize(row * static_cast<std::size_t>(height));
  // OpenGL's rows run bottom to top.
  for (int y = 0; y < height; ++y) {
    std::memcpy(out.rgb.data() + static_cast<std::size_t>(y) * row,
                pixels->GetPointer(0) + static_cast<std::size_t>(height - 1 - y) * row, row);
  }
  return Status::ok();
}

Status SceneRenderer::render(const pipeline::PipelineDescription& d, const SceneInput& input,
                             Image& out) {
  CRACKVIS_RETURN_IF_ERROR(setScene(d, input, true));
  return renderFrame(d.view.width, d.view.height, out);
}

void SceneRenderer::setImpostorOptions(const ImpostorOptions& options) {
  m_impl->impostorOptions = options;
  m_impl->applyImpostorOptions();
}

SceneRenderer::ImpostorStats SceneRenderer::impostorStats() const {
  const vtkPointSpriteSphereMapper* mapper = m_impl->impostors;
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

void resample(const Image& in, int width, int height, Image& out) {
  out.width = width;
  out.height = height;
  // Capacity beyond the pixels: swscale reads RGB rows in whole SIMD blocks.
  out.rgb.reserve(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 3 + 256);
  out.rgb.resize(static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 3);
  std::vector<int> sourceX(static_cast<std::size_t>(width));
  for (int x = 0; x < width; ++x) {
    sourceX[static_cast<std::size_t>(x)] = std::min(in.width - 1, x * in.width / width);
  }
  for (int y = 0; y < height; ++y) {
    const int sy = std::min(in.height - 1, y * in.height / height);
    const std::uint8_t* source = in.pixel(0, sy);
    std::uint8_t* target = out.rgb.data() + static_cast<std::size_t>(y) * width * 3;
    for (int x = 0; x < width; ++x) {
      std::memcpy(target + 3 * x, source + 3 * sourceX[static_cast<std::size_t>(x)], 3);
    }
  }
}

namespace {

// VTK's images run bottom to top.
vtkSmartPointer<vtkImageData> toImageData(const Image& image) {
  auto data = vtkSmartPointer<vtkImageData>::New();
  data->SetDimensions(image.width, image.height, 1);
  data->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  auto* target = static_cast<std::uint8_t*>(data->GetScalarPointer());
  const std::size_t row = static_cast<std::size_t>(image.width) * 3;
  for (int y = 0; y < image.height; ++y) {
    std::memcpy(target + static_cast<std::size_t>(y) * row,
                image.rgb.data() + static_cast<std::size_t>(image.height - 1 - y) * row, row);
  }
  return data;
}

}  // namespace

Status writePng(const Image& image, const std::string& path) {
  // Encoded in memory and written beside its name, renamed over it when
  // complete: a full disk leaves an existing picture as it was, and libpng
  // never writes (nor prints its write errors) itself.
  auto png = encodePng(image);
  if (!png) {
    return png.status();
  }
  return replaceFile(path,
                     std::string_view(reinterpret_cast<const char*>(png->data()), png->size()));
}

Result<std::vector<std::uint8_t>> encodePng(const Image& image) {
  if (image.width < 1 || image.height < 1) {
    return invalidArgument("an empty image has no PNG");
  }
  const VtkErrorScope vtkErrors;
  vtkNew<vtkPNGWriter> writer;
  writer->WriteToMemoryOn();
  writer->SetInputData(toImageData(image));
  writer->Write();
  vtkUnsignedCharArray* bytes = writer->GetResult();
  if (const Status vtk = vtkErrors.status("vtkPNGWriter");
      writer->GetErrorCode() != 0 || bytes == nullptr || !vtk) {
    return internalError(
        fmt::format("the PNG encoder failed ({})", vtk ? "no detail from VTK" : vtk.message()));
  }
  const auto* first = bytes->GetPointer(0);
  return std::vector<std::uint8_t>(first, first + bytes->GetNumberOfValues());
}

}  // namespace crackvis::render
