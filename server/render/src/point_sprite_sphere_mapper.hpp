// Sphere impostors without a geometry shader: one GL point per sphere, sized
// in the vertex shader (gl_PointSize) to cover the sphere's projected
// silhouette; the fragment shader casts the pixel's view ray at the sphere,
// discards the pixels that miss it, lights the hit with the sphere's normal
// and writes its depth (gl_FragDepth), so spheres cut each other and the
// surfaces around them. A drop-in replacement for vtkOpenGLSphereMapper
// (the same radius array, scalar colouring, clipping planes, perspective and
// parallel cameras, the inside of translucent spheres).
//
// Before each draw the spheres that cannot show are left out on the CPU
// (sphere_occlusion.hpp): spheres a clipping plane removes and, for an
// opaque actor, spheres hidden behind others. The picture is the same.
// GL drops a point whose centre leaves the viewport, so the points are drawn
// into a viewport wider by half the largest point (a guard band), scissored
// to the real one: a sphere at the picture's edge shows the part in it.
//
// Points wider than the GL implementation's largest point size (llvmpipe:
// 255 pixels) cannot be drawn: a frame with such a sphere in view is drawn
// by vtkOpenGLSphereMapper's geometry shader (a camera close to a few
// particles), still without the spheres left out.
#pragma once

#include <cstdint>
#include <vector>

#include <vtkNew.h>
#include <vtkOpenGLBufferObject.h>
#include <vtkOpenGLSphereMapper.h>

#include <crackvis/render/sphere_occlusion.hpp>

namespace crackvis::render {

class vtkPointSpriteSphereMapper : public vtkOpenGLSphereMapper {
 public:
  static vtkPointSpriteSphereMapper* New();
  vtkTypeMacro(vtkPointSpriteSphereMapper, vtkOpenGLSphereMapper);

  // Leave out spheres hidden behind others (default on).
  vtkSetMacro(OcclusionCulling, bool);
  vtkGetMacro(OcclusionCulling, bool);
  // Always draw with the geometry shader, as vtkOpenGLSphereMapper does (off).
  vtkSetMacro(ForceGeometryShader, bool);
  vtkGetMacro(ForceGeometryShader, bool);
  // Spheres from which occlusion culling goes by cells of spheres kept
  // between frames (SphereCells); tests force either way.
  void SetOcclusionCellThreshold(std::size_t spheres) { this->OcclusionCellThreshold = spheres; }

  // The last frame: how many spheres were drawn, of how many, and whether
  // as points (false: the geometry shader).
  std::int64_t GetLastDrawnCount() const { return this->LastDrawnCount; }
  std::int64_t GetLastSphereCount() const { return this->LastSphereCount; }
  bool GetLastDrewPoints() const { return this->LastDrewPoints; }

  void ReleaseGraphicsResources(vtkWindow* window) override;

 protected:
  vtkPointSpriteSphereMapper() = default;
  ~vtkPointSpriteSphereMapper() override = default;

  void GetShaderTemplate(std::map<vtkShader::Type, vtkShader*> shaders, vtkRenderer* ren,
                         vtkActor* act) override;
  void ReplaceShaderValues(std::map<vtkShader::Type, vtkShader*> shaders, vtkRenderer* ren,
                           vtkActor* act) override;
  bool GetNeedToRebuildShaders(vtkOpenGLHelper& cellBO, vtkRenderer* ren, vtkActor* act) override;
  void SetCameraShaderParameters(vtkOpenGLHelper& cellBO, vtkRenderer* ren, vtkActor* act) override;
  void RenderPieceDraw(vtkRenderer* ren, vtkActor* act) override;
  // The centres' bounds widened by the largest radius, so that VTK's
  // frustum culling and clipping range see the spheres whole.
  void ComputeBounds() override;

 private:
  vtkPointSpriteSphereMapper(const vtkPointSpriteSphereMapper&) = delete;
  void operator=(const vtkPointSpriteSphereMapper&) = delete;

  // Chooses this frame's way (DrawPoints) and the spheres to draw
  // (this->Drawn). guard: the guard band of points.
  void SelectSpheres(vtkRenderer* ren, vtkActor* act, const int viewport[4], int guard);
  // Groups the input's spheres into cells again when they changed.
  void UpdateCells(vtkDataArray* positions, vtkDataArray* radii);

  bool OcclusionCulling = true;
  bool ForceGeometryShader = false;
  bool DrawPoints = true;         // this frame's way
  bool ShadersArePoints = false;  // the way the current shaders draw
  float MaxPointSize = 0.0f;      // GL_ALIASED_POINT_SIZE_RANGE's upper end; 0 until queried
  // This frame's spheres no clipping plane removes: their indices, and in
  // view coordinates.
  std::vector<std::uint32_t> Candidates;
  std::vector<double> X, Y, Z;
  std::vector<float> Radii;
  std::vector<std::uint8_t> MayHide;
  SphereOcclusion Occlusion;
  std::size_t OcclusionCellThreshold = 16384;
  SphereCells Cells;
  // What Cells were built from: the arrays and their modification times.
  struct CellsSource {
    vtkDataArray* positions = nullptr;
    vtkMTimeType positionsTime = 0;
    vtkDataArray* radii = nullptr;
    vtkMTimeType radiiTime = 0;
    double radius = 0.0;
    bool operator==(const CellsSource&) const = default;
  };
  CellsSource CellsBuiltFrom;
  std::vector<std::uint32_t> Drawn;
  vtkNew<vtkOpenGLBufferObject> DrawnIndices;
  using DrawElementsFunction = void (*)(unsigned int mode, int count, unsigned int type,
                                        const void* indices);
  DrawElementsFunction DrawElements = nullptr;  // glDrawElements
  std::int64_t LastDrawnCount = 0;
  std::int64_t LastSphereCount = 0;
  bool LastDrewPoints = true;
};

}  // namespace crackvis::render
