// The VTK actors and mappers of a scene's layers (scene_actors.hpp).
#include "scene_actors.hpp"

#include <algorithm>
#include <array>
#include <cstring>
#include <optional>
#include <span>

#include <crackvis_vtk_conversion.h>
#include <vtkActor.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDataSetMapper.h>
#include <vtkDoubleArray.h>
#include <vtkFloatArray.h>
#include <vtkIdTypeArray.h>
#include <vtkLookupTable.h>
#include <vtkNew.h>
#include <vtkPlane.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyDataMapper.h>
#include <vtkProperty.h>
#include <vtkRenderer.h>
#include <vtkTubeFilter.h>
#include <vtkUnstructuredGrid.h>

#include "overlays.hpp"
#include "point_sprite_sphere_mapper.hpp"
#include <crackvis/render/scene_renderer.hpp>
#include <crackvis/scene_model/scene_content.hpp>

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
    case pipeline::ParticleColourBy::kFragment:
      return "fragment";
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
}  // namespace

namespace detail {

double meanRadius(std::span<const double> radius) {
  double sum = 0.0;
  for (double r : radius) {
    sum += r;
  }
  return radius.empty() ? 1.0 : sum / static_cast<double>(radius.size());
}

vtkSmartPointer<vtkActor> particleActor(const pipeline::PipelineDescription& d,
                                        const SceneInput& input, std::vector<Legend>* legends) {
  const auto& particles = d.particles;
  const std::vector<dem::ParticleIndex> visible = scene::visibleParticles(particles, input);
  const auto n = static_cast<vtkIdType>(visible.size());
  // The arrays are written through their pointers: per-value calls (virtual
  // for the points, a growing cell array) took most of the scene's time at
  // 1e6 particles and more.
  vtkNew<vtkDoubleArray> xyz;
  xyz->SetNumberOfComponents(3);
  xyz->SetNumberOfTuples(n);
  vtkNew<vtkIdTypeArray> offsets;
  offsets->SetNumberOfValues(n + 1);
  vtkNew<vtkIdTypeArray> connectivity;
  connectivity->SetNumberOfValues(n);
  vtkNew<vtkFloatArray> radius;
  radius->SetName(kSphereRadiusArray);
  radius->SetNumberOfValues(n);
  double* point = xyz->GetPointer(0);
  vtkIdType* offset = offsets->GetPointer(0);
  vtkIdType* vertex = connectivity->GetPointer(0);
  float* r = radius->GetPointer(0);
  for (vtkIdType k = 0; k < n; ++k) {
    const auto i = static_cast<std::size_t>(visible[static_cast<std::size_t>(k)]);
    const dem::Vec3& p = input.step.positions[i];
    point[3 * k] = p.x;
    point[3 * k + 1] = p.y;
    point[3 * k + 2] = p.z;
    offset[k] = k;
    vertex[k] = k;
    r[k] = static_cast<float>(input.step.radius[i]);
  }
  offset[n] = n;
  vtkNew<vtkPoints> points;
  points->SetData(xyz);
  auto data = vtkSmartPointer<vtkPolyData>::New();
  data->SetPoints(points);
  // The impostor mapper draws vertex cells: one per particle.
  vtkNew<vtkCellArray> vertices;
  vertices->SetData(offsets, connectivity);
  data->SetVerts(vertices);
  data->GetPointData()->AddArray(radius);
  vtkNew<vtkDoubleArray> values;
  // The array's name in the scene: an extra array's own.
  values->SetName(particles.colourBy == pipeline::ParticleColourBy::kExtra
                      ? particles.colourByExtra.c_str()
                      : particleArrayName(particles.colourBy));
  const auto perParticle = scene::particleValues(particles, input);
  values->SetNumberOfValues(n);
  double* value = values->GetPointer(0);
  for (vtkIdType k = 0; k < n; ++k) {
    value[k] = perParticle[static_cast<std::size_t>(visible[static_cast<std::size_t>(k)])];
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
    spheres->SetScaleArray(kSphereRadiusArray);
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
// Crack primitives of broken, consistent bonds; the local Voronoi
// inconsistency marks (lines between the particle centres) and intact faces
// (the local decomposition) as separate actors when the description shows them.
// Returns the crack primitives' actor (the renderer holds it).
vtkActor* addCracks(const pipeline::PipelineDescription& d, const SceneInput& input,
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
  return actor;
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

}  // namespace detail
}  // namespace crackvis::render
