#include <fmt/format.h>

#include <crackvis/vocabulary/crack_method.hpp>

namespace crackvis::cracks {

std::string_view toString(Method method) {
  switch (method) {
    case Method::kCellAttribute:
      return "cell-attribute";
    case Method::kCellCut:
      return "cell-cut";
    case Method::kLocalVoronoi:
      return "local-voronoi";
    case Method::kCellCentre:
      return "cell-centre";
  }
  return "unknown";
}

Result<Method> parseMethod(std::string_view name) {
  for (auto method :
       {Method::kCellAttribute, Method::kCellCut, Method::kLocalVoronoi, Method::kCellCentre}) {
    if (name == toString(method)) {
      return method;
    }
  }
  return invalidArgument(fmt::format(
      "unknown method '{}' (expected cell-attribute, cell-cut, local-voronoi or cell-centre)",
      name));
}

std::string_view toString(Decomposition decomposition) {
  switch (decomposition) {
    case Decomposition::kAuto:
      return "auto";
    case Decomposition::kLattice:
      return "lattice";
    case Decomposition::kTriangulation:
      return "triangulation";
  }
  return "unknown";
}

Result<Decomposition> parseDecomposition(std::string_view name) {
  for (auto kind : {Decomposition::kAuto, Decomposition::kLattice, Decomposition::kTriangulation}) {
    if (name == toString(kind)) {
      return kind;
    }
  }
  return invalidArgument(
      fmt::format("unknown decomposition '{}' (expected auto, lattice or triangulation)", name));
}

}  // namespace crackvis::cracks
