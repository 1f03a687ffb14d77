// Writing crack meshes for ParaView, VisIt and FEA pre-processors.
//
//  - .vtp: VTK XML PolyData (vertices, lines, polygons, all attributes);
//  - .vtu: VTK XML UnstructuredGrid, used when the mesh has volume cells
//    (the cell attribute method in 3D), with the other primitives as cells too;
//  - .pvd: a ParaView collection of per-step files with their times;
//  - .stl: binary STL of the polygons (and of volume cells' faces), triangulated
//    as fans; lines, vertices and attributes have no place in STL;
//  - .obj: Wavefront OBJ with polygons (f), lines (l) and vertices (p).
// VTK XML files use appended raw little-endian data with 64-bit headers.
#pragma once

#include <string>
#include <vector>

#include <crackvis/common/status.hpp>
#include <crackvis/cracks/crack_mesh.hpp>

namespace crackvis::cracks {

// The VTK XML extension a mesh needs: "vtu" with volume cells, else "vtp".
std::string vtkExtensionFor(const CrackMesh& mesh);

Status writeVtkXml(const CrackMesh& mesh, const std::string& path);
Status writeStl(const CrackMesh& mesh, const std::string& path);
Status writeObj(const CrackMesh& mesh, const std::string& path);

// Writes by extension (.vtp, .vtu, .stl, .obj).
Status writeMesh(const CrackMesh& mesh, const std::string& path);

struct CollectionEntry {
  double time;
  std::string file;  // relative to the .pvd's folder
};
// Consecutive entries of the same time become parts 0, 1, ... of that step.
Status writePvd(const std::vector<CollectionEntry>& entries, const std::string& path);

}  // namespace crackvis::cracks
