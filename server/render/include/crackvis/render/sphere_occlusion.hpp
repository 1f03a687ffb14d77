// Which sphere impostors of a frame can show, decided on the CPU before the
// draw. An impostor writes its depth (gl_FragDepth), so no GPU can skip the
// fragments of a sphere hidden behind others, and llvmpipe shades every one
// of them; in a block of particles seen from outside most spheres are
// hidden. SphereOcclusion rasterizes the spheres front to back into a depth
// buffer at the pixels' centres (where the GPU samples) and leaves a sphere
// out when, at every pixel its point covers, a sphere already drawn is
// nearer than the sphere's nearest point. Conservative: a sphere left out
// could not have changed a pixel, so the picture is the same with or
// without it.
//
// Also the point size of a sphere impostor (spriteDiameter), shared with the
// vertex shader of vtkPointSpriteSphereMapper.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

namespace crackvis::render {

// The camera as seen from the viewport's pixels. View coordinates: the eye
// at the origin looking down -z; depth below means distance in front of the
// eye plane (-z). The ray through the centre of pixel (i, j) (i + 0.5,
// j + 0.5 from the viewport's lower left corner) has q = (i + 0.5, j + 0.5)
// * rayScale + rayOffset: perspective: direction (q, -1) from the eye;
// parallel: origin (q, 0), direction (0, 0, -1).
struct OcclusionView {
  bool parallel = false;
  int width = 0;  // viewport, pixels
  int height = 0;
  std::array<double, 2> rayScale{};
  std::array<double, 2> rayOffset{};
  double nearDepth = 0.0;  // the clipping range
  double farDepth = 0.0;
};

// The spheres of a frame in view coordinates, structure of arrays.
struct SphereSet {
  std::span<const double> x, y, z;
  std::span<const float> radius;
  // 0 for a sphere that may not be drawn (clipped by a plane): it hides
  // nothing. Empty: all may hide.
  std::span<const std::uint8_t> mayHide;
};

// The point size, in pixels, that covers a sphere's silhouette: its centre
// `centre` (view coordinates) projects to the point's centre; the
// silhouette's extent along x and y comes from the planes through the eye
// that touch the sphere. scale: OcclusionView::rayScale. Infinite for a
// sphere the eye plane cuts; 0 for one behind the eye.
double spriteDiameter(const std::array<double, 3>& centre, double radius, bool parallel,
                      const std::array<double, 2>& scale);

// Keeps its buffers from frame to frame. Not thread-safe.
//
// Above cellThreshold spheres in view (1e6-particle specimens) the spheres
// are first binned into cells of a grid in view space, about 64 to a cell;
// cells go front to back by their nearest sphere, a cell whose every pixel
// is already nearer than its nearest sphere is left out whole, and the
// spheres of the others go front to back within their cell. The interior of
// a block then costs a test per cell instead of a sort and a test per
// sphere. It may keep a few spheres the sorted order would leave out (one
// farther away drawn before what hides it), never fewer: the picture is the
// same.
class SphereOcclusion {
 public:
  // Projects a frame's spheres (viewed, not copied: they must outlive
  // unoccluded()). Returns the widest point, in pixels, that a sphere in
  // view needs (infinite for one the eye plane cuts).
  double project(const OcclusionView& view, const SphereSet& spheres);
  // The indices of the spheres that may show, ascending: spheres whose point
  // misses the viewport and spheres hidden behind others are left out.
  // guard: how far beyond the viewport, in pixels, a point's centre may be
  // and the point still drawn (GL drops a point whose centre is outside the
  // viewport it is drawn into).
  const std::vector<std::int32_t>& unoccluded(int guard);
  // Spheres in view from which on cells are used (tests force either way).
  void setCellThreshold(std::size_t spheres) { m_cellThreshold = spheres; }

 private:
  struct Projected {
    double u = 0.0, v = 0.0;  // the point's centre, pixels
    double half = 0.0;        // half its side, pixels
    double front = 0.0;       // the sphere's nearest depth
    bool inView = false;
  };
  struct PixelBox {
    int i0 = 0, i1 = -1, j0 = 0, j1 = -1;  // pixel index ranges, inclusive
  };
  struct Cell {
    // Its spheres' points, pixels: the union of u +- half, v +- half.
    double lo[2] = {std::numeric_limits<double>::infinity(),
                    std::numeric_limits<double>::infinity()};
    double hi[2] = {-std::numeric_limits<double>::infinity(),
                    -std::numeric_limits<double>::infinity()};
    PixelBox box;
    float front = std::numeric_limits<float>::infinity();
    std::int32_t first = 0;  // its spheres in m_cellSpheres
    std::int32_t count = 0;
  };
  PixelBox pixelsIn(double uLo, double uHi, double vLo, double vHi) const;
  PixelBox pixelsOf(const Projected& p) const;
  // Projects sphere i; returns the widest point in view so far.
  double projectOne(std::size_t i, double largest);
  // Whether every pixel of `box` already holds a depth nearer than `limit`.
  bool covered(const PixelBox& box, float limit) const;
  // Draws sphere i into the depth buffer when it may hide others.
  void drawSphere(std::size_t i, const PixelBox& box, int guard);
  // Tests sphere i against the depth buffer; keeps and draws it if it shows.
  void visit(std::size_t i, int guard);
  void cellOrder(int guard);

  std::size_t m_cellThreshold = 65536;
  std::vector<Cell> m_cells;
  std::vector<std::int32_t> m_cellOf;       // per sphere in view
  std::vector<std::int32_t> m_cellSpheres;  // sphere indices, grouped by cell
  std::vector<std::int32_t> m_cellOrder;
  OcclusionView m_view;
  SphereSet m_spheres;
  std::vector<Projected> m_projected;
  std::vector<std::uint64_t> m_order;
  std::vector<std::uint64_t> m_orderScratch;  // the radix sort's other buffer
  std::vector<float> m_nearest;               // per pixel
  std::vector<float> m_tileFarthest;
  std::vector<std::uint8_t> m_keep;
  std::vector<std::int32_t> m_visible;
};

// One frame without keeping buffers: project, then unoccluded(0).
std::vector<std::int32_t> unoccludedSpheres(const OcclusionView& view, const SphereSet& spheres);

}  // namespace crackvis::render
