#include <cstring>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>

#include <crackvis/common/pending_file.hpp>
#include <crackvis/cracks/lattice_cells.hpp>
#include <crackvis/cracks/mesh_writers.hpp>

// Every file is written beside its name and renamed over it when complete
// (replaceFile): a full disk leaves an existing file as it was.
namespace crackvis::cracks {
namespace {

// Collects the appended-data blocks of a VTK XML file and their offsets.
class AppendedData {
 public:
  template <typename T>
  std::uint64_t add(const std::vector<T>& values) {
    const std::uint64_t offset = m_bytes.size();
    const std::uint64_t size = values.size() * sizeof(T);
    append(&size, sizeof size);
    append(values.data(), size);
    return offset;
  }
  const std::string& bytes() const { return m_bytes; }

 private:
  void append(const void* data, std::size_t size) {
    m_bytes.append(static_cast<const char*>(data), size);
  }
  std::string m_bytes;
};

const char* vtkTypeName(AttributeType type) {
  switch (type) {
    case AttributeType::kInt32:
      return "Int32";
    case AttributeType::kFloat32:
      return "Float32";
    case AttributeType::kFloat64:
      return "Float64";
  }
  return "Float64";
}

std::string dataArray(const char* type, const std::string& name, int components,
                      std::uint64_t offset) {
  return fmt::format(
      R"(        <DataArray type="{}" Name="{}" NumberOfComponents="{}" format="appended" offset="{}"/>
)",
      type, name, components, offset);
}

std::string attributeArrays(const std::vector<AttributeArray>& arrays, AppendedData& data) {
  std::string xml;
  for (const AttributeArray& array : arrays) {
    std::uint64_t offset = 0;
    switch (array.type) {
      case AttributeType::kInt32:
        offset = data.add(std::vector<std::int32_t>(array.values.begin(), array.values.end()));
        break;
      case AttributeType::kFloat32:
        offset = data.add(std::vector<float>(array.values.begin(), array.values.end()));
        break;
      case AttributeType::kFloat64:
        offset = data.add(array.values);
        break;
    }
    xml += dataArray(vtkTypeName(array.type), array.name, array.components, offset);
  }
  return xml;
}

std::vector<double> flatPoints(const std::vector<Vec3>& points) {
  std::vector<double> flat(points.size() * 3);
  if (!flat.empty()) {  // memcpy from an empty vector's null data is undefined
    std::memcpy(flat.data(), points.data(), flat.size() * sizeof(double));
  }
  return flat;
}

std::vector<std::int32_t> endOffsets(const PrimitiveList& list) {
  return {list.offsets.begin() + 1, list.offsets.end()};
}

std::string finish(const std::string& type, const std::string& piece, const AppendedData& data) {
  return fmt::format(R"(<?xml version="1.0"?>
<VTKFile type="{0}" version="1.0" byte_order="LittleEndian" header_type="UInt64">
  <{0}>
{1}  </{0}>
  <AppendedData encoding="raw">
   _)",
                     type, piece) +
         data.bytes() + "\n  </AppendedData>\n</VTKFile>\n";
}

std::string polyDataXml(const CrackMesh& mesh) {
  AppendedData data;
  std::string piece = fmt::format(
      R"(    <Piece NumberOfPoints="{}" NumberOfVerts="{}" NumberOfLines="{}" NumberOfStrips="0" NumberOfPolys="{}">
)",
      mesh.points.size(), mesh.vertices.size(), mesh.lines.size(), mesh.polygons.size());
  piece += "      <PointData>\n" + attributeArrays(mesh.pointData, data) + "      </PointData>\n";
  piece += "      <CellData>\n" + attributeArrays(mesh.cellData, data) + "      </CellData>\n";
  piece += "      <Points>\n" +
           dataArray("Float64", "Points", 3, data.add(flatPoints(mesh.points))) +
           "      </Points>\n";
  std::vector<std::int32_t> vertexOffsets(mesh.vertices.size());
  for (std::size_t k = 0; k < vertexOffsets.size(); ++k) {
    vertexOffsets[k] = static_cast<std::int32_t>(k + 1);
  }
  auto section = [&](const char* name, const std::vector<std::int32_t>& connectivity,
                     const std::vector<std::int32_t>& offsets) {
    return fmt::format("      <{}>\n", name) +
           dataArray("Int32", "connectivity", 1, data.add(connectivity)) +
           dataArray("Int32", "offsets", 1, data.add(offsets)) + fmt::format("      </{}>\n", name);
  };
  piece += section("Verts", mesh.vertices, vertexOffsets);
  piece += section("Lines", mesh.lines.connectivity, endOffsets(mesh.lines));
  piece += section("Polys", mesh.polygons.connectivity, endOffsets(mesh.polygons));
  piece += "    </Piece>\n";
  return finish("PolyData", piece, data);
}

std::string unstructuredGridXml(const CrackMesh& mesh) {
  // Every primitive becomes a cell, in the order of the cell data.
  std::vector<std::int32_t> connectivity;
  std::vector<std::int32_t> offsets;
  std::vector<std::uint8_t> types;
  auto add = [&](const std::int32_t* ids, std::size_t count, std::uint8_t type) {
    connectivity.insert(connectivity.end(), ids, ids + count);
    offsets.push_back(static_cast<std::int32_t>(connectivity.size()));
    types.push_back(type);
  };
  for (std::int32_t v : mesh.vertices) {
    add(&v, 1, 1);  // VTK_VERTEX
  }
  auto addList = [&](const PrimitiveList& list, std::uint8_t type) {
    for (std::size_t k = 0; k < list.size(); ++k) {
      add(list.connectivity.data() + list.offsets[k],
          static_cast<std::size_t>(list.offsets[k + 1] - list.offsets[k]), type);
    }
  };
  addList(mesh.lines, 4);     // VTK_POLY_LINE
  addList(mesh.polygons, 7);  // VTK_POLYGON
  for (std::size_t k = 0; k < mesh.volumeCells.size(); ++k) {
    add(mesh.volumeCells.connectivity.data() + mesh.volumeCells.offsets[k],
        static_cast<std::size_t>(mesh.volumeCells.offsets[k + 1] - mesh.volumeCells.offsets[k]),
        mesh.volumeCellTypes[k]);
  }
  AppendedData data;
  std::string piece = fmt::format(R"(    <Piece NumberOfPoints="{}" NumberOfCells="{}">
)",
                                  mesh.points.size(), types.size());
  piece += "      <PointData>\n" + attributeArrays(mesh.pointData, data) + "      </PointData>\n";
  piece += "      <CellData>\n" + attributeArrays(mesh.cellData, data) + "      </CellData>\n";
  piece += "      <Points>\n" +
           dataArray("Float64", "Points", 3, data.add(flatPoints(mesh.points))) +
           "      </Points>\n";
  piece += "      <Cells>\n" + dataArray("Int32", "connectivity", 1, data.add(connectivity)) +
           dataArray("Int32", "offsets", 1, data.add(offsets)) +
           dataArray("UInt8", "types", 1, data.add(types)) + "      </Cells>\n";
  piece += "    </Piece>\n";
  return finish("UnstructuredGrid", piece, data);
}

// Faces of every polygon and volume cell, as point-id cycles.
template <typename Visit>
void forEachFace(const CrackMesh& mesh, Visit&& visit) {
  std::vector<std::int32_t> face;
  for (std::size_t k = 0; k < mesh.polygons.size(); ++k) {
    face.assign(mesh.polygons.connectivity.begin() + mesh.polygons.offsets[k],
                mesh.polygons.connectivity.begin() + mesh.polygons.offsets[k + 1]);
    visit(face);
  }
  for (std::size_t k = 0; k < mesh.volumeCells.size(); ++k) {
    const std::int32_t* nodes = mesh.volumeCells.connectivity.data() + mesh.volumeCells.offsets[k];
    const CellType type =
        mesh.volumeCellTypes[k] == 14 ? CellType::kPyramid : CellType::kTetrahedron;
    const CellShape& shape = shapeOf(type);
    for (int f = 0; f < shape.faceCount; ++f) {
      face.clear();
      for (int v = 0; v < shape.faceSizes[static_cast<std::size_t>(f)]; ++v) {
        face.push_back(
            nodes[shape.faces[static_cast<std::size_t>(f)][static_cast<std::size_t>(v)]]);
      }
      visit(face);
    }
  }
}

bool endsWith(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

std::string vtkExtensionFor(const CrackMesh& mesh) {
  return mesh.hasVolumeCells() ? "vtu" : "vtp";
}

Status writeVtkXml(const CrackMesh& mesh, const std::string& path) {
  // ParaView picks the reader by the extension: an UnstructuredGrid in a
  // .vtp name is a file it cannot open.
  if (mesh.hasVolumeCells() && !endsWith(path, ".vtu")) {
    return invalidArgument(fmt::format(
        "{}: these cracks have volume cells (the cell attribute method in 3D), which only an "
        "UnstructuredGrid holds: name the output .vtu",
        path));
  }
  return replaceFile(path, endsWith(path, ".vtu") ? unstructuredGridXml(mesh) : polyDataXml(mesh));
}

Status writeStl(const CrackMesh& mesh, const std::string& path) {
  std::string body;
  std::uint32_t triangles = 0;
  forEachFace(mesh, [&](const std::vector<std::int32_t>& face) {
    for (std::size_t k = 1; k + 1 < face.size(); ++k) {
      const Vec3 a = mesh.points[static_cast<std::size_t>(face[0])];
      const Vec3 b = mesh.points[static_cast<std::size_t>(face[k])];
      const Vec3 c = mesh.points[static_cast<std::size_t>(face[k + 1])];
      Vec3 n = cross(b - a, c - a);
      const double length = dem::norm(n);
      n = length > 0 ? (1.0 / length) * n : Vec3{};
      const float record[12] = {
          static_cast<float>(n.x), static_cast<float>(n.y), static_cast<float>(n.z),
          static_cast<float>(a.x), static_cast<float>(a.y), static_cast<float>(a.z),
          static_cast<float>(b.x), static_cast<float>(b.y), static_cast<float>(b.z),
          static_cast<float>(c.x), static_cast<float>(c.y), static_cast<float>(c.z)};
      body.append(reinterpret_cast<const char*>(record), sizeof record);
      body.append(2, '\0');  // attribute byte count
      ++triangles;
    }
  });
  std::string header(80, ' ');
  const std::string title = "crackvis crack surface";
  header.replace(0, title.size(), title);
  header.append(reinterpret_cast<const char*>(&triangles), sizeof triangles);
  return replaceFile(path, header + body);
}

Status writeObj(const CrackMesh& mesh, const std::string& path) {
  std::string text = "# crackvis crack surface\n";
  for (const Vec3& p : mesh.points) {
    text += fmt::format("v {:.17g} {:.17g} {:.17g}\n", p.x, p.y, p.z);
  }
  for (std::int32_t v : mesh.vertices) {
    text += fmt::format("p {}\n", v + 1);
  }
  for (std::size_t k = 0; k < mesh.lines.size(); ++k) {
    text += "l";
    for (auto i = mesh.lines.offsets[k]; i < mesh.lines.offsets[k + 1]; ++i) {
      text += fmt::format(" {}", mesh.lines.connectivity[static_cast<std::size_t>(i)] + 1);
    }
    text += "\n";
  }
  forEachFace(mesh, [&](const std::vector<std::int32_t>& face) {
    text += "f";
    for (std::int32_t v : face) {
      text += fmt::format(" {}", v + 1);
    }
    text += "\n";
  });
  return replaceFile(path, text);
}

Status writeMesh(const CrackMesh& mesh, const std::string& path) {
  if (endsWith(path, ".vtp") || endsWith(path, ".vtu")) {
    return writeVtkXml(mesh, path);
  }
  if (endsWith(path, ".stl")) {
    return writeStl(mesh, path);
  }
  if (endsWith(path, ".obj")) {
    return writeObj(mesh, path);
  }
  return invalidArgument(
      fmt::format("{}: unknown output format (expected .vtp, .vtu, .stl or .obj)", path));
}

Status writePvd(const std::vector<CollectionEntry>& entries, const std::string& path) {
  std::string text =
      "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\" "
      "byte_order=\"LittleEndian\">\n  <Collection>\n";
  // Entries of one time in a row are parts of that step (particles, bonds).
  int part = 0;
  for (std::size_t i = 0; i < entries.size(); ++i) {
    part = i > 0 && entries[i].time == entries[i - 1].time ? part + 1 : 0;
    text += fmt::format("    <DataSet timestep=\"{:.17g}\" group=\"\" part=\"{}\" file=\"{}\"/>\n",
                        entries[i].time, part, entries[i].file);
  }
  text += "  </Collection>\n</VTKFile>\n";
  return replaceFile(path, text);
}

}  // namespace crackvis::cracks
