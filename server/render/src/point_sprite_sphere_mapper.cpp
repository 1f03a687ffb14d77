#include "point_sprite_sphere_mapper.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <ios>
#include <span>

#include <EGL/egl.h>
#include <vtkActor.h>
#include <vtkCamera.h>
#include <vtkDataArray.h>
#include <vtkDoubleArray.h>
#include <vtkFloatArray.h>
#include <vtkMath.h>
#include <vtkMatrix4x4.h>
#include <vtkObjectFactory.h>
#include <vtkOpenGLCamera.h>
#include <vtkOpenGLHelper.h>
#include <vtkOpenGLRenderWindow.h>
#include <vtkOpenGLState.h>
#include <vtkOpenGLVertexBufferObjectGroup.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkRenderer.h>
#include <vtkShader.h>
#include <vtkShaderProgram.h>
#include <vtk_glew.h>

namespace crackvis::render {

vtkStandardNewMacro(vtkPointSpriteSphereMapper);

namespace {

// The vertex shader of the point path: the sphere's centre and radius in view
// coordinates for the fragment shader (flat: the same for all its pixels),
// and a point just wide enough for the silhouette. A perspective silhouette
// is an ellipse off the projected centre; its extent along x comes from the
// two planes through the eye and the y axis that touch the sphere (likewise
// for y), and the point, centred on the projected centre, covers the farther
// side. Keep in step with spriteDiameter() (sphere_occlusion.cpp).
constexpr const char* kPointSpriteVS = R"(//VTK::System::Dec
in vec4 vertexMC;
in float radiusMC;
uniform mat4 MCVCMatrix;
uniform mat4 VCDCMatrix;
uniform int cameraParallel;
uniform vec4 rayFromPixel;
uniform float maxPointSize;
uniform vec2 clipScale;
flat out vec4 sphereVCVSOutput;

//VTK::CustomUniforms::Dec

//VTK::Color::Dec

//VTK::Clip::Dec

//VTK::Picking::Dec

void main()
{
  //VTK::Color::Impl

  //VTK::Clip::Impl

  vec4 centre = MCVCMatrix * vertexMC;
  centre /= centre.w;
  float r = radiusMC;
  sphereVCVSOutput = vec4(centre.xyz, r);
  gl_Position = VCDCMatrix * centre;
  gl_Position.xy *= clipScale;
  vec2 halfExtent = vec2(r);
  if (cameraParallel == 0)
  {
    float a = centre.z * centre.z - r * r;
    vec2 c = abs(centre.xy);
    halfExtent = a > 0.0 ? (c * (r * r / abs(centre.z)) + r * sqrt(c * c + vec2(a))) / a
                         : vec2(1.0e30);
  }
  vec2 pixels = 2.0 * halfExtent / abs(rayFromPixel.xy);
  gl_PointSize = min(max(pixels.x, pixels.y) + 1.0, maxPointSize);

  //VTK::Picking::Impl
}
)";

// The fragment shader's parts. The pixel's view ray: o + t d with d.z = -1,
// so that t is the hit's distance in front of the eye plane; rayFromPixel
// maps gl_FragCoord to the ray's x, y at unit distance (perspective) or to
// its origin (parallel), which is exact for any projection VTK makes.
constexpr const char* kPositionDec =
    "uniform vec4 rayFromPixel;\n"
    "flat in vec4 sphereVCVSOutput;\n";
constexpr const char* kPositionImpl =
    "vec2 rayXY = gl_FragCoord.xy * rayFromPixel.xy + rayFromPixel.zw;\n"
    "  vec3 rayOrigin = vec3(cameraParallel != 0 ? rayXY : vec2(0.0), 0.0);\n"
    "  vec3 rayDir = vec3(cameraParallel != 0 ? vec2(0.0) : rayXY, -1.0);\n"
    "  vec4 vertexVC = vec4(rayOrigin, 1.0);\n";
constexpr const char* kNormalDec =
    "uniform float invertedDepth;\n"
    "uniform mat4 VCDCMatrix;\n";
// The nearer root of |o + t d - c|^2 = r^2 (the farther for the inside of a
// translucent sphere), from the ray's point nearest the centre: the offset
// between the two is small and exact, where |o - c|^2 - r^2 would lose the
// sphere's size to rounding for a small sphere far from the eye. No hit, no
// pixel.
constexpr const char* kDepthImpl =
    "vec3 fromCentre = rayOrigin - sphereVCVSOutput.xyz;\n"
    "  float dd = dot(rayDir, rayDir);\n"
    "  float closest = -dot(rayDir, fromCentre) / dd;\n"
    "  vec3 offset = fromCentre + closest * rayDir;\n"
    "  float chord2 = sphereVCVSOutput.w * sphereVCVSOutput.w - dot(offset, offset);\n"
    "  if (chord2 < 0.0) { discard; }\n"
    "  float t = closest - invertedDepth * sqrt(chord2 / dd);\n"
    "  vertexVC.xyz = rayOrigin + t * rayDir;\n"
    "  vec3 normalVCVSOutput = (invertedDepth / sphereVCVSOutput.w) * "
    "(vertexVC.xyz - sphereVCVSOutput.xyz);\n"
    "  vec2 clipZW = (VCDCMatrix * vertexVC).zw;\n"
    "  gl_FragDepth = 0.5 * clipZW.x / clipZW.y + 0.5;\n";

// The camera as the viewport's pixels see it (sphere_occlusion.hpp).
OcclusionView occlusionView(vtkRenderer* ren, const int viewport[4]) {
  vtkCamera* camera = ren->GetActiveCamera();
  vtkMatrix4x4* wcvc = nullptr;
  vtkMatrix3x3* normals = nullptr;
  vtkMatrix4x4* vcdc = nullptr;
  vtkMatrix4x4* wcdc = nullptr;
  static_cast<vtkOpenGLCamera*>(camera)->GetKeyMatrices(ren, wcvc, normals, vcdc, wcdc);
  OcclusionView view;
  view.parallel = camera->GetParallelProjection() != 0;
  view.width = viewport[2];
  view.height = viewport[3];
  // vcdc is kept transposed for GL: element (j, i) is the projection's (i, j).
  // Perspective: ndc.x = p00 x / -z - p02, so x / -z = (ndc.x + p02) / p00;
  // parallel: ndc.x = p00 x + p03. And ndc = 2 pixel / size - 1.
  for (int axis = 0; axis < 2; ++axis) {
    const double scale = vcdc->GetElement(axis, axis);
    const double shift = view.parallel ? vcdc->GetElement(3, axis) : -vcdc->GetElement(2, axis);
    view.rayScale[axis] = 2.0 / (viewport[2 + axis] * scale);
    view.rayOffset[axis] = (-1.0 - shift) / scale;
  }
  double range[2];
  camera->GetClippingRange(range);
  view.nearDepth = range[0];
  view.farDepth = range[1];
  return view;
}

}  // namespace

void vtkPointSpriteSphereMapper::GetShaderTemplate(std::map<vtkShader::Type, vtkShader*> shaders,
                                                   vtkRenderer* ren, vtkActor* act) {
  if (!this->DrawPoints) {
    this->Superclass::GetShaderTemplate(shaders, ren, act);
    return;
  }
  vtkOpenGLPolyDataMapper::GetShaderTemplate(shaders, ren, act);
  shaders[vtkShader::Vertex]->SetSource(kPointSpriteVS);
  shaders[vtkShader::Geometry]->SetSource("");
}

void vtkPointSpriteSphereMapper::ReplaceShaderValues(std::map<vtkShader::Type, vtkShader*> shaders,
                                                     vtkRenderer* ren, vtkActor* act) {
  this->ShadersArePoints = this->DrawPoints;
  if (!this->DrawPoints) {
    this->Superclass::ReplaceShaderValues(shaders, ren, act);
    return;
  }
  std::string fs = shaders[vtkShader::Fragment]->GetSource();
  vtkShaderProgram::Substitute(fs, "//VTK::PositionVC::Dec", kPositionDec);
  vtkShaderProgram::Substitute(fs, "//VTK::PositionVC::Impl", kPositionImpl);
  vtkShaderProgram::Substitute(fs, "//VTK::Normal::Dec", kNormalDec);
  vtkShaderProgram::Substitute(fs, "//VTK::Depth::Impl", kDepthImpl);
  // The normal comes with the depth.
  vtkShaderProgram::Substitute(fs, "//VTK::Normal::Impl", "");
  shaders[vtkShader::Fragment]->SetSource(fs);
  // vtkOpenGLSphereMapper's own replacements are for its geometry shader.
  vtkOpenGLPolyDataMapper::ReplaceShaderValues(shaders, ren, act);
}

bool vtkPointSpriteSphereMapper::GetNeedToRebuildShaders(vtkOpenGLHelper& cellBO, vtkRenderer* ren,
                                                         vtkActor* act) {
  // Evaluated first: the superclass records the lighting it saw.
  const bool changed = this->Superclass::GetNeedToRebuildShaders(cellBO, ren, act);
  return changed || this->ShadersArePoints != this->DrawPoints;
}

void vtkPointSpriteSphereMapper::SetCameraShaderParameters(vtkOpenGLHelper& cellBO,
                                                           vtkRenderer* ren, vtkActor* act) {
  this->Superclass::SetCameraShaderParameters(cellBO, ren, act);
  vtkShaderProgram* program = cellBO.Program;
  if (program->IsUniformUsed("rayFromPixel")) {
    int viewport[4];
    static_cast<vtkOpenGLRenderWindow*>(ren->GetRenderWindow())
        ->GetState()
        ->vtkglGetIntegerv(GL_VIEWPORT, viewport);
    const OcclusionView view = occlusionView(ren, viewport);
    // From the viewport's pixels to the window's (gl_FragCoord).
    const float ray[4] = {static_cast<float>(view.rayScale[0]),
                          static_cast<float>(view.rayScale[1]),
                          static_cast<float>(view.rayOffset[0] - viewport[0] * view.rayScale[0]),
                          static_cast<float>(view.rayOffset[1] - viewport[1] * view.rayScale[1])};
    program->SetUniform4f("rayFromPixel", ray);
  }
  if (program->IsUniformUsed("maxPointSize")) {
    program->SetUniformf("maxPointSize", this->MaxPointSize);
  }
}

void vtkPointSpriteSphereMapper::ComputeBounds() {
  this->Superclass::ComputeBounds();
  if (!vtkMath::AreBoundsInitialized(this->Bounds)) {
    return;
  }
  double largest = this->Radius;
  vtkPolyData* poly = this->GetInput();
  if (vtkDataArray* radii = this->ScaleArray != nullptr && poly != nullptr
                                ? poly->GetPointData()->GetArray(this->ScaleArray)
                                : nullptr) {
    largest = radii->GetNumberOfTuples() > 0 ? radii->GetRange(0)[1] : 0.0;
  }
  for (int k = 0; k < 3; ++k) {
    this->Bounds[2 * k] -= std::max(largest, 0.0);
    this->Bounds[2 * k + 1] += std::max(largest, 0.0);
  }
}

void vtkPointSpriteSphereMapper::ReleaseGraphicsResources(vtkWindow* window) {
  this->DrawnIndices->ReleaseGraphicsResources();
  this->Superclass::ReleaseGraphicsResources(window);
}

void vtkPointSpriteSphereMapper::UpdateCells(vtkDataArray* positions, vtkDataArray* radii) {
  const CellsSource source{positions, positions->GetMTime(), radii,
                           radii != nullptr ? radii->GetMTime() : 0, this->Radius};
  if (source == this->CellsBuiltFrom) {
    return;
  }
  const auto n = static_cast<std::size_t>(positions->GetNumberOfTuples());
  std::vector<double> xyz;
  std::span<const double> centres;
  if (auto* doubles = vtkDoubleArray::FastDownCast(positions)) {
    centres = {doubles->GetPointer(0), 3 * n};
  } else {
    xyz.resize(3 * n);
    for (std::size_t i = 0; i < n; ++i) {
      positions->GetTuple(static_cast<vtkIdType>(i), xyz.data() + 3 * i);
    }
    centres = xyz;
  }
  std::vector<float> sizes;
  std::span<const float> radius;
  if (auto* floats = vtkFloatArray::FastDownCast(radii)) {
    radius = {floats->GetPointer(0), n};
  } else {
    sizes.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      sizes[i] = radii != nullptr
                     ? static_cast<float>(radii->GetComponent(static_cast<vtkIdType>(i), 0))
                     : static_cast<float>(this->Radius);
    }
    radius = sizes;
  }
  this->Cells.build(centres, radius);
  this->CellsBuiltFrom = source;
}

void vtkPointSpriteSphereMapper::SelectSpheres(vtkRenderer* ren, vtkActor* act,
                                               const int viewport[4], int guard) {
  vtkPolyData* poly = this->CurrentInput;
  vtkDataArray* positions = poly->GetPoints()->GetData();
  const vtkIdType n = positions->GetNumberOfTuples();
  vtkDataArray* radii =
      this->ScaleArray != nullptr ? poly->GetPointData()->GetArray(this->ScaleArray) : nullptr;
  const OcclusionView view = occlusionView(ren, viewport);
  vtkNew<vtkMatrix4x4> mcvc;  // untransposed
  vtkMatrix4x4::Multiply4x4(ren->GetActiveCamera()->GetModelViewTransformMatrix(), act->GetMatrix(),
                            mcvc);
  ModelToView transform;
  for (int row = 0; row < 3; ++row) {
    for (int column = 0; column < 4; ++column) {
      transform.rows[row][column] = mcvc->GetElement(row, column);
    }
  }
  std::vector<ClipPlane> planes(static_cast<std::size_t>(this->GetNumberOfClippingPlanes()));
  for (std::size_t k = 0; k < planes.size(); ++k) {
    this->GetClippingPlaneInDataCoords(act->GetMatrix(), static_cast<int>(k), planes[k].data());
  }
  transform.planes = planes;
  const bool culling = this->OcclusionCulling && !act->HasTranslucentPolygonalGeometry() &&
                       ren->GetSelector() == nullptr;

  if (static_cast<std::size_t>(n) >= this->OcclusionCellThreshold) {
    // Large sets: by cells kept between frames, no sphere projected unless
    // its cell needs it. Without culling (a GPU), the cells in view are
    // drawn whole.
    this->UpdateCells(positions, radii);
    const double largest =
        this->Occlusion.projectCells(view, this->Cells, transform, this->MaxPointSize);
    this->DrawPoints = !this->ForceGeometryShader && largest <= this->MaxPointSize;
    const std::vector<std::int32_t>& shown =
        culling ? this->Occlusion.unoccludedInCells(this->DrawPoints ? guard : 0)
                : this->Occlusion.inViewCells();
    this->Drawn.assign(shown.begin(), shown.end());
    return;
  }

  // The spheres no clipping plane removes, in view coordinates.
  this->Candidates.clear();
  this->X.clear();
  this->Y.clear();
  this->Z.clear();
  this->Radii.clear();
  this->MayHide.clear();
  auto* doubles = vtkDoubleArray::FastDownCast(positions);
  auto* floatRadii = vtkFloatArray::FastDownCast(radii);
  for (vtkIdType i = 0; i < n; ++i) {
    std::array<double, 3> p;
    if (doubles != nullptr) {
      std::copy_n(doubles->GetPointer(3 * i), 3, p.data());
    } else {
      positions->GetTuple(i, p.data());
    }
    const ClipTest clip = clipCentre(planes, p);
    if (clip.clipped) {
      continue;
    }
    this->Candidates.push_back(static_cast<std::uint32_t>(i));
    const std::array<double, 3> q = transform.apply(p);
    this->X.push_back(q[0]);
    this->Y.push_back(q[1]);
    this->Z.push_back(q[2]);
    this->Radii.push_back(floatRadii != nullptr ? floatRadii->GetValue(i)
                          : radii != nullptr    ? static_cast<float>(radii->GetComponent(i, 0))
                                                : this->Radius);
    this->MayHide.push_back(clip.nearPlane ? 0 : 1);
  }
  const double largest = this->Occlusion.project(
      view, SphereSet{this->X, this->Y, this->Z, this->Radii, this->MayHide});
  this->DrawPoints = !this->ForceGeometryShader && largest <= this->MaxPointSize;

  if (culling) {
    const std::vector<std::int32_t>& shown =
        this->Occlusion.unoccluded(this->DrawPoints ? guard : 0);
    this->Drawn.clear();
    for (const std::int32_t k : shown) {
      this->Drawn.push_back(this->Candidates[static_cast<std::size_t>(k)]);
    }
  } else {
    this->Drawn = this->Candidates;
  }
}

void vtkPointSpriteSphereMapper::RenderPieceDraw(vtkRenderer* ren, vtkActor* act) {
  const int count = this->VBOs->GetNumberOfTuples("vertexMC");
  this->LastSphereCount = count;
  this->LastDrawnCount = 0;
  if (count == 0) {
    return;
  }
  // The draw call comes through EGL: GL's own libraries are VTK's to link.
  if (this->DrawElements == nullptr) {
    this->DrawElements =
        reinterpret_cast<DrawElementsFunction>(eglGetProcAddress("glDrawElements"));
    if (this->DrawElements == nullptr) {
      vtkErrorMacro(<< "eglGetProcAddress(\"glDrawElements\") failed: EGL error 0x" << std::hex
                    << eglGetError());
      return;
    }
  }
  vtkOpenGLState* state = static_cast<vtkOpenGLRenderWindow*>(ren->GetRenderWindow())->GetState();
  if (this->MaxPointSize == 0.0f) {
    GLfloat range[2] = {1.0f, 1.0f};
    state->vtkglGetFloatv(GL_ALIASED_POINT_SIZE_RANGE, range);
    this->MaxPointSize = range[1];
  }
  int viewport[4];
  state->vtkglGetIntegerv(GL_VIEWPORT, viewport);
  // GL drops a point whose centre is outside the viewport, however wide:
  // the points are drawn into a viewport wider by half the largest point
  // on each side (a guard band), scissored to the real one.
  const int guard = static_cast<int>(std::ceil(0.5 * this->MaxPointSize)) + 1;
  this->SelectSpheres(ren, act, viewport, guard);
  this->UpdateShaders(this->Primitives[PrimitiveTris], ren, act);
  if (this->Drawn.empty()) {
    this->LastDrewPoints = this->DrawPoints;
    return;
  }
  vtkOpenGLState::ScopedglViewport savedViewport(state);
  vtkOpenGLState::ScopedglScissor savedScissor(state);
  vtkOpenGLState::ScopedglEnableDisable savedScissorTest(state, GL_SCISSOR_TEST);
  if (this->DrawPoints) {
    const float clipScale[2] = {
        static_cast<float>(viewport[2]) / static_cast<float>(viewport[2] + 2 * guard),
        static_cast<float>(viewport[3]) / static_cast<float>(viewport[3] + 2 * guard)};
    this->Primitives[PrimitiveTris].Program->SetUniform2f("clipScale", clipScale);
    state->vtkglScissor(viewport[0], viewport[1], viewport[2], viewport[3]);
    state->vtkglEnable(GL_SCISSOR_TEST);
    state->vtkglViewport(viewport[0] - guard, viewport[1] - guard, viewport[2] + 2 * guard,
                         viewport[3] + 2 * guard);
    state->vtkglEnable(GL_PROGRAM_POINT_SIZE);
  }
  // The VAO bound by UpdateShaders keeps the index buffer.
  this->DrawnIndices->Upload(this->Drawn, vtkOpenGLBufferObject::ElementArrayBuffer);
  this->DrawnIndices->Bind();
  this->DrawElements(GL_POINTS, static_cast<GLsizei>(this->Drawn.size()), GL_UNSIGNED_INT, nullptr);
  this->DrawnIndices->Release();
  if (this->DrawPoints) {
    state->vtkglDisable(GL_PROGRAM_POINT_SIZE);
  }
  this->LastDrawnCount = static_cast<std::int64_t>(this->Drawn.size());
  this->LastDrewPoints = this->DrawPoints;
}

}  // namespace crackvis::render
