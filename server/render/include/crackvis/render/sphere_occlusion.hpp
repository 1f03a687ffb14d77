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

// A clipping plane e: a point p is kept where e0 p.x + e1 p.y + e2 p.z + e3
// >= 0 (model coordinates).
using ClipPlane = std::array<double, 4>;

// What the clipping planes do to a sphere centred at p: the fragment shader
// drops a sphere whose centre a plane puts below 0; near 0 the GPU's float
// arithmetic decides, so such a sphere is drawn but may hide nothing.
struct ClipTest {
  bool clipped = false;
  bool nearPlane = false;
};
ClipTest clipCentre(std::span<const ClipPlane> planes, const std::array<double, 3>& p);

// The spheres of a data set in model coordinates, grouped into cells of
// about 64 neighbours (a grid over their centres) and kept from frame to
// frame while the spheres do not move: a frame then projects and tests
// cells, and only the spheres of cells that may show. Members are copied in
// cell order, so a cell's spheres are contiguous in memory.
class SphereCells {
 public:
  struct Cell {
    std::array<double, 3> centre{};  // of the box of its sphere centres
    double spread = 0.0;             // the farthest centre from `centre`
    float largestRadius = 0.0f;
    std::int32_t first = 0;  // its members
    std::int32_t count = 0;
  };
  // xyz: 3 per sphere, interleaved; radius: one per sphere.
  void build(std::span<const double> xyz, std::span<const float> radius);
  std::size_t sphereCount() const { return m_index.size(); }
  const std::vector<Cell>& cells() const { return m_cells; }
  // Members in cell order: the sphere's index, its centre, its radius.
  std::int32_t index(std::size_t member) const { return m_index[member]; }
  const std::array<double, 3>& centre(std::size_t member) const { return m_centre[member]; }
  float radius(std::size_t member) const { return m_radius[member]; }
  std::size_t memoryBytes() const;

 private:
  std::vector<Cell> m_cells;
  std::vector<std::int32_t> m_index;
  std::vector<std::array<double, 3>> m_centre;
  std::vector<float> m_radius;
};

// From model to view coordinates: the rows of the 3x4 affine matrix, and the
// clipping planes in model coordinates. Radii are not transformed (as the
// impostor shaders draw them).
struct ModelToView {
  std::array<std::array<double, 4>, 3> rows{};
  std::span<const ClipPlane> planes;

  std::array<double, 3> apply(const std::array<double, 3>& p) const {
    std::array<double, 3> out{};
    for (int row = 0; row < 3; ++row) {
      const auto& m = rows[static_cast<std::size_t>(row)];
      out[static_cast<std::size_t>(row)] = m[0] * p[0] + m[1] * p[1] + m[2] * p[2] + m[3];
    }
    return out;
  }
};

// Keeps its buffers from frame to frame. Not thread-safe.
//
// Two ways to one answer:
//  - sphere by sphere (project, unoccluded): every sphere in view is
//    projected, sorted front to back and tested;
//  - by cells (projectCells, unoccludedInCells), for large data sets
//    (1e6-particle specimens): cells go front to back by their bounding
//    sphere; a cell whose bounding sphere's pixels all hold a nearer depth
//    already is left out whole, unprojected; the spheres of the others go
//    front to back within their cell. The interior of a block then costs a
//    test per cell instead of a projection, a sort and a test per sphere.
//    The two may keep slightly different spheres (cells go by their
//    silhouettes, spheres by their points; a farther sphere may be drawn
//    before what hides it), but each leaves out only spheres that change no
//    pixel: the picture is the same.
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

  // By cells: projects the cells of `cells` (viewed: they must outlive
  // unoccludedInCells()) and returns the widest point a sphere in view may
  // need, exact where it matters: a cell whose bound exceeds `pointLimit`
  // (or that the eye plane cuts) has its spheres projected one by one.
  double projectCells(const OcclusionView& view, const SphereCells& cells,
                      const ModelToView& transform, double pointLimit);
  // The indices (SphereCells' input order) of the spheres that may show,
  // ascending; clipped spheres are left out.
  const std::vector<std::int32_t>& unoccludedInCells(int guard);
  // By cells, without the occlusion test: the spheres of every cell in view
  // after projectCells, clipped spheres left out, ascending. For a GPU,
  // which draws a hidden sphere faster than the CPU can find it hidden. A
  // cell out of view is not drawn; the cost is a byte per sphere, marked and
  // scanned.
  const std::vector<std::int32_t>& inViewCells();

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
  enum class Clip : std::uint8_t { kNone, kSome };
  struct CellInView {
    PixelBox box;  // the pixels its bounding sphere covers
    float front = 0.0f;
    bool open = false;  // its spheres are tested one by one, the cell not
    Clip clip = Clip::kNone;
    std::int32_t cell = 0;
    std::int32_t first = 0;  // an open cell's spheres, projected already
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
  // Clears the depth buffer and its tiles.
  void clearDepth();
  // Transforms, clip-tests and projects the spheres of a cell into the
  // frame's sphere arrays; returns the widest point in view.
  double appendCell(const CellInView& cell, double largest);
  // Visits the spheres [first, first + count) of the frame's arrays front to
  // back.
  void visitInOrder(std::int32_t first, std::int32_t count, int guard);

  OcclusionView m_view;
  SphereSet m_spheres;
  std::vector<Projected> m_projected;
  std::vector<std::uint64_t> m_order;
  std::vector<std::uint64_t> m_orderScratch;  // the radix sort's other buffer
  std::vector<float> m_nearest;               // per pixel
  std::vector<float> m_tileFarthest;
  std::vector<std::uint8_t> m_keep;
  std::vector<std::int32_t> m_visible;
  // By cells: the cells in view, and the spheres projected this frame
  // (their view coordinates and the index each came from).
  const SphereCells* m_cellSet = nullptr;
  ModelToView m_transform;
  std::vector<ClipPlane> m_planes;
  std::vector<CellInView> m_cellsInView;
  std::vector<double> m_x, m_y, m_z;
  std::vector<float> m_radius;
  std::vector<std::uint8_t> m_mayHide;
  std::vector<std::int32_t> m_source;
  std::vector<std::int32_t> m_cellSpheres;
  std::vector<std::uint8_t> m_inView;  // per sphere, inViewCells()
};

// One frame without keeping buffers: project, then unoccluded(0).
std::vector<std::int32_t> unoccludedSpheres(const OcclusionView& view, const SphereSet& spheres);

}  // namespace crackvis::render
