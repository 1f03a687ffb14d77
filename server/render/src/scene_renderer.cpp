#include <algorithm>
#include <cmath>
#include <cstring>

#include <crackvis_vtk_conversion.h>
#include <fmt/format.h>
#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDoubleArray.h>
#include <vtkFloatArray.h>
#include <vtkGenericOpenGLRenderWindow.h>
#include <vtkImageData.h>
#include <vtkLookupTable.h>
#include <vtkNew.h>
#include <vtkOpenGLSphereMapper.h>
#include <vtkPNGWriter.h>
#include <vtkPlane.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderer.h>
#include <vtkRendererCollection.h>
#include <vtkUnsignedCharArray.h>

#include <crackvis/render/egl_context.hpp>
#include <crackvis/render/scene_renderer.hpp>

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

void colourByScalars(vtkPolyDataMapper* mapper, vtkDataArray* scalars, bool cellData,
                     ColourMap map) {
  double range[2] = {0, 1};
  scalars->GetRange(range);
  mapper->SetLookupTable(lookupTable(map, range[0], range[1]));
  mapper->SetScalarRange(range[0], range[1] > range[0] ? range[1] : range[0] + 1.0);
  mapper->SetScalarModeToUsePointFieldData();
  if (cellData) {
    mapper->SetScalarModeToUseCellFieldData();
  }
  mapper->SelectColorArray(scalars->GetName());
  mapper->ScalarVisibilityOn();
}

// The per-particle value a colour-by names.
std::vector<double> particleValues(const pipeline::ParticlesDescription& particles,
                                   const SceneInput& input) {
  const std::size_t n = input.step.positions.size();
  std::vector<double> values(n, 0.0);
  switch (particles.colourBy) {
    case pipeline::ParticleColourBy::kRadius:
      std::copy(input.step.radius.begin(), input.step.radius.end(), values.begin());
      break;
    case pipeline::ParticleColourBy::kDisplacement:
      for (std::size_t i = 0; i < n && i < input.initialPositions.size(); ++i) {
        values[i] = dem::norm(input.step.positions[i] - input.initialPositions[i]);
      }
      break;
    case pipeline::ParticleColourBy::kVelocity:
      for (std::size_t i = 0; i < n && i < input.velocities.size(); ++i) {
        const auto& v = input.velocities[i];
        values[i] = std::sqrt(double{v[0]} * v[0] + double{v[1]} * v[1] + double{v[2]} * v[2]);
      }
      break;
    case pipeline::ParticleColourBy::kDamage: {
      // Share of a particle's bonds that are broken.
      std::vector<int> bonds(n, 0);
      std::vector<int> broken(n, 0);
      for (std::size_t b = 0; b < input.lattice->bonds.size(); ++b) {
        for (auto end : {input.lattice->bonds[b].first, input.lattice->bonds[b].second}) {
          ++bonds[static_cast<std::size_t>(end)];
          broken[static_cast<std::size_t>(end)] += input.step.bondState[b] != 0 ? 1 : 0;
        }
      }
      for (std::size_t i = 0; i < n; ++i) {
        values[i] = bonds[i] > 0 ? static_cast<double>(broken[i]) / bonds[i] : 0.0;
      }
      break;
    }
    case pipeline::ParticleColourBy::kSolid:
      break;
  }
  return values;
}

vtkSmartPointer<vtkActor> particleActor(const pipeline::PipelineDescription& d,
                                        const SceneInput& input) {
  const auto& particles = d.particles;
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  const auto n = static_cast<vtkIdType>(input.step.positions.size());
  points->SetNumberOfPoints(n);
  std::memcpy(vtkDoubleArray::SafeDownCast(points->GetData())->GetPointer(0),
              input.step.positions.data(), static_cast<std::size_t>(n) * sizeof(dem::Vec3));
  auto data = vtkSmartPointer<vtkPolyData>::New();
  data->SetPoints(points);
  // The impostor mapper draws vertex cells: one per particle.
  vtkNew<vtkCellArray> vertices;
  for (vtkIdType i = 0; i < n; ++i) {
    vertices->InsertNextCell(1, &i);
  }
  data->SetVerts(vertices);
  vtkNew<vtkFloatArray> radius;
  radius->SetName("radius");
  radius->SetNumberOfValues(n);
  for (vtkIdType i = 0; i < n; ++i) {
    radius->SetValue(i, static_cast<float>(input.step.radius[static_cast<std::size_t>(i)]));
  }
  data->GetPointData()->AddArray(radius);
  vtkNew<vtkDoubleArray> values;
  values->SetName("value");
  const auto perParticle = particleValues(particles, input);
  values->SetNumberOfValues(n);
  for (vtkIdType i = 0; i < n; ++i) {
    values->SetValue(i, perParticle[static_cast<std::size_t>(i)]);
  }
  data->GetPointData()->AddArray(values);

  vtkSmartPointer<vtkPolyDataMapper> mapper;
  if (particles.representation == pipeline::ParticleRepresentation::kImpostors) {
    auto spheres = vtkSmartPointer<vtkOpenGLSphereMapper>::New();
    spheres->SetScaleArray("radius");
    mapper = spheres;
  } else {
    mapper = vtkSmartPointer<vtkPolyDataMapper>::New();
  }
  mapper->SetInputData(data);
  mapper->ScalarVisibilityOff();
  if (particles.colourBy != pipeline::ParticleColourBy::kSolid) {
    colourByScalars(mapper, values, false, d.view.colourMap);
  }
  if (particles.clip) {
    vtkNew<vtkPlane> plane;
    plane->SetOrigin(particles.clip->origin.x, particles.clip->origin.y, particles.clip->origin.z);
    // VTK keeps the side the normal points to; the description hides it.
    plane->SetNormal(-particles.clip->normal.x, -particles.clip->normal.y,
                     -particles.clip->normal.z);
    mapper->AddClippingPlane(plane);
  }
  auto actor = vtkSmartPointer<vtkActor>::New();
  actor->SetMapper(mapper);
  setColour(actor->GetProperty(), particles.colour);
  actor->GetProperty()->SetOpacity(particles.opacity);
  if (particles.representation == pipeline::ParticleRepresentation::kPoints) {
    actor->GetProperty()->SetPointSize(3);
  }
  return actor;
}

const char* crackArrayName(pipeline::CrackColourBy by) {
  switch (by) {
    case pipeline::CrackColourBy::kBondId:
      return "bond_id";
    case pipeline::CrackColourBy::kForce:
      return "bond_force";
    case pipeline::CrackColourBy::kBreakStep:
      return "break_step";
    case pipeline::CrackColourBy::kState:
      return "bond_state";
    case pipeline::CrackColourBy::kSolid:
      break;
  }
  return nullptr;
}

// Crack primitives, and (separately) the local Voronoi inconsistency marks.
void addCracks(const pipeline::PipelineDescription& d, const cracks::CrackMesh& mesh,
               vtkRenderer* renderer) {
  auto data = vtkSmartPointer<vtkPolyData>::New();
  cracks::vtkadapter::toPolyData(mesh, data);
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputData(data);
  mapper->ScalarVisibilityOff();
  if (const char* name = crackArrayName(d.cracks.colourBy)) {
    if (vtkDataArray* cells = data->GetCellData()->GetArray(name)) {
      colourByScalars(mapper, cells, true, d.view.colourMap);
    } else if (vtkDataArray* points = data->GetPointData()->GetArray(name)) {
      colourByScalars(mapper, points, false, d.view.colourMap);
    }
  }
  vtkNew<vtkActor> actor;
  actor->SetMapper(mapper);
  setColour(actor->GetProperty(), d.cracks.colour);
  actor->GetProperty()->SetOpacity(d.cracks.opacity);
  actor->GetProperty()->SetLineWidth(2.0);
  actor->GetProperty()->SetPointSize(4.0);
  actor->GetProperty()->BackfaceCullingOff();
  renderer->AddActor(actor);
}

void addBonds(const pipeline::PipelineDescription& d, const SceneInput& input,
              vtkRenderer* renderer) {
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  for (const dem::Vec3& p : input.step.positions) {
    points->InsertNextPoint(p.x, p.y, p.z);
  }
  vtkNew<vtkCellArray> lines;
  vtkNew<vtkDoubleArray> values;
  values->SetName("value");
  for (std::size_t b = 0; b < input.lattice->bonds.size(); ++b) {
    const bool broken = input.step.bondState[b] != 0;
    if (d.bonds.show == pipeline::BondSelection::kBroken && !broken) {
      continue;
    }
    const vtkIdType ids[2] = {input.lattice->bonds[b].first, input.lattice->bonds[b].second};
    lines->InsertNextCell(2, ids);
    double value = broken ? 1.0 : 0.0;
    if (d.bonds.colourBy == pipeline::BondColourBy::kForce && !input.step.bondForce.empty()) {
      value = input.step.bondForce[b];
    } else if (d.bonds.colourBy == pipeline::BondColourBy::kBreakStep &&
               !input.step.breakStep.empty()) {
      value = input.step.breakStep[b];
    }
    values->InsertNextValue(value);
  }
  vtkNew<vtkPolyData> data;
  data->SetPoints(points);
  data->SetLines(lines);
  data->GetCellData()->AddArray(values);
  vtkNew<vtkPolyDataMapper> mapper;
  mapper->SetInputData(data);
  mapper->ScalarVisibilityOff();
  if (d.bonds.colourBy != pipeline::BondColourBy::kSolid) {
    colourByScalars(mapper, values, true, d.view.colourMap);
  }
  vtkNew<vtkActor> actor;
  actor->SetMapper(mapper);
  setColour(actor->GetProperty(), d.bonds.colour);
  actor->GetProperty()->SetLineWidth(2.0);
  renderer->AddActor(actor);
}

}  // namespace

struct SceneRenderer::Impl {
  std::unique_ptr<EglContext> egl;
  vtkSmartPointer<vtkGenericOpenGLRenderWindow> window;
  vtkSmartPointer<vtkRenderer> renderer;  // the scene on the window now
  int width = 0;
  int height = 0;
};

SceneRenderer::SceneRenderer() : m_impl(std::make_unique<Impl>()) {}
SceneRenderer::~SceneRenderer() {
  if (m_impl && m_impl->egl) {
    (void)m_impl->egl->makeCurrent();
    m_impl->renderer = nullptr;
    m_impl->window = nullptr;  // GL resources go while the context is current
  }
}

Result<std::unique_ptr<SceneRenderer>> SceneRenderer::create(int width, int height) {
  auto egl = EglContext::create(width, height);
  if (!egl) {
    return egl.status();
  }
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
  impl.window->Render();
  const char* capabilities = impl.window->ReportCapabilities();
  if (capabilities == nullptr || std::string(capabilities).find("OpenGL") == std::string::npos) {
    return failedPrecondition(
        fmt::format("{}: VTK could not initialize OpenGL on it", impl.egl->description()));
  }
  std::string glRenderer = "unknown";
  if (capabilities != nullptr) {
    const std::string text = capabilities;
    const auto at = text.find("OpenGL renderer string:");
    if (at != std::string::npos) {
      glRenderer = text.substr(at + 24, text.find('\n', at) - at - 24);
    }
  }
  renderer->m_backend = fmt::format("{}; OpenGL renderer: {}", impl.egl->description(), glRenderer);
  return renderer;
}

Status SceneRenderer::render(const pipeline::PipelineDescription& d, const SceneInput& input,
                             Image& out) {
  Impl& impl = *m_impl;
  if (d.view.width != impl.width || d.view.height != impl.height) {
    return invalidArgument(fmt::format("view {}x{} does not match the renderer's {}x{}",
                                       d.view.width, d.view.height, impl.width, impl.height));
  }
  CRACKVIS_RETURN_IF_ERROR(impl.egl->makeCurrent());
  auto renderer = vtkSmartPointer<vtkRenderer>::New();
  renderer->SetBackground(d.view.background.r / 255.0, d.view.background.g / 255.0,
                          d.view.background.b / 255.0);
  if (d.particles.visible) {
    renderer->AddActor(particleActor(d, input));
  }
  if (d.cracks.visible && input.cracks != nullptr) {
    addCracks(d, *input.cracks, renderer);
  }
  if (d.bonds.show != pipeline::BondSelection::kNone) {
    addBonds(d, input, renderer);
  }
  impl.window->RemoveRenderer(impl.renderer);
  impl.renderer = renderer;
  impl.window->AddRenderer(renderer);
  if (d.view.camera) {
    vtkCamera* camera = renderer->GetActiveCamera();
    const auto& c = *d.view.camera;
    camera->SetPosition(c.position.x, c.position.y, c.position.z);
    camera->SetFocalPoint(c.focalPoint.x, c.focalPoint.y, c.focalPoint.z);
    camera->SetViewUp(c.viewUp.x, c.viewUp.y, c.viewUp.z);
    camera->SetViewAngle(c.viewAngle);
    renderer->ResetCameraClippingRange();
  } else {
    renderer->ResetCamera();
  }
  impl.window->Render();
  vtkNew<vtkUnsignedCharArray> pixels;
  impl.window->GetPixelData(0, 0, impl.width - 1, impl.height - 1, 0, pixels, 0);
  out.width = impl.width;
  out.height = impl.height;
  out.rgb.resize(static_cast<std::size_t>(impl.width) * static_cast<std::size_t>(impl.height) * 3);
  // OpenGL's rows run bottom to top.
  const std::size_t row = static_cast<std::size_t>(impl.width) * 3;
  for (int y = 0; y < impl.height; ++y) {
    std::memcpy(out.rgb.data() + static_cast<std::size_t>(y) * row,
                pixels->GetPointer(0) + static_cast<std::size_t>(impl.height - 1 - y) * row, row);
  }
  return Status::ok();
}

Status writePng(const Image& image, const std::string& path) {
  vtkNew<vtkImageData> data;
  data->SetDimensions(image.width, image.height, 1);
  data->AllocateScalars(VTK_UNSIGNED_CHAR, 3);
  auto* target = static_cast<std::uint8_t*>(data->GetScalarPointer());
  const std::size_t row = static_cast<std::size_t>(image.width) * 3;
  for (int y = 0; y < image.height; ++y) {  // VTK images also run bottom to top
    std::memcpy(target + static_cast<std::size_t>(y) * row,
                image.rgb.data() + static_cast<std::size_t>(image.height - 1 - y) * row, row);
  }
  vtkNew<vtkPNGWriter> writer;
  writer->SetFileName(path.c_str());
  writer->SetInputData(data);
  writer->Write();
  if (writer->GetErrorCode() != 0) {
    return failedPrecondition(fmt::format("{}: cannot write the PNG", path));
  }
  return Status::ok();
}

}  // namespace crackvis::render
