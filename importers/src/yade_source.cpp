// Yade: the series VTKRecorder writes with recorders ['spheres', 'id',
// 'intr', 'jcfpm'] (spheres.<iter>.vtu, intrs.<iter>.vtp; any file name
// prefix), read with VTK's own XML readers so binary, appended and
// compressed files all work, plus the JCFpm crack recorder's text file
// (cracks_<Key>.txt) where present.
//
// The interaction file carries no particle ids: its points are the bodies'
// positions. They are matched to the spheres' points, which VTKRecorder
// writes from the same state, so the coordinates agree exactly.
#include <algorithm>
#include <charconv>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <unordered_map>

#include <fmt/format.h>
#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkIdList.h>
#include <vtkNew.h>
#include <vtkObject.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLUnstructuredGridReader.h>

#include "text_input.hpp"
#include <crackvis/importers/step_source.hpp>

namespace crackvis::importers {
namespace {

struct RecordName {
  std::string prefix;  // the path up to "spheres." / "intrs."
  std::int64_t iteration = 0;
};

// "<prefix>spheres.<iter>.vtu" or "<prefix>intrs.<iter>.vtp".
std::optional<RecordName> parseRecordName(const std::string& path, std::string_view kind,
                                          std::string_view extension) {
  const std::string name = baseName(path);
  const std::size_t at = name.rfind(kind);
  if (at == std::string::npos || name.size() <= at + kind.size() + extension.size() ||
      name.compare(name.size() - extension.size(), extension.size(), extension) != 0) {
    return std::nullopt;
  }
  RecordName record;
  const std::string_view digits = std::string_view(name).substr(
      at + kind.size(), name.size() - extension.size() - at - kind.size());
  if (digits.empty() || !std::all_of(digits.begin(), digits.end(), ::isdigit) ||
      !parseId(digits, record.iteration)) {
    return std::nullopt;
  }
  record.prefix = path.substr(0, path.size() - name.size() + at);
  return record;
}

// VTKRecorder's other recorders ('cracks', 'facets', ...): "<prefix>cracks.<iter>.vtu". They
// hold nothing crackvis imports (it extracts its own crack surfaces), so
// they are skipped with a note, whether found in a folder or named.
std::optional<std::string> otherRecorder(const std::string& path) {
  for (const char* kind : {"cracks", "facets", "boxes", "pericell", "moments", "polyhedra",
                           "pFacets", "polyhedralIntr", "liqcontrol"}) {
    for (const char* extension : {".vtu", ".vtp"}) {
      if (parseRecordName(path, std::string(kind) + ".", extension)) {
        return kind;
      }
    }
  }
  return std::nullopt;
}

// VTK's XML readers allocate every array by the counts in the file's
// header (NumberOfPoints="...") before they read a byte of data, so a
// corrupt or hostile header of 400 million points in a 12 KB file cost
// gigabytes. A count is believed only as far as the file could hold its
// data: a point is 12 bytes at least (three float32), any other element 4,
// and zlib never compresses more than about 1032:1.
Status checkDeclaredCounts(const std::string& path) {
  constexpr std::uint64_t kMaxExpansion = 1100;
  std::ifstream in(path, std::ios::binary);
  std::string head(64 * 1024, '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  head.resize(static_cast<std::size_t>(in.gcount()));
  std::error_code error;
  const std::uintmax_t fileBytes = std::filesystem::file_size(path, error);
  if (error) {
    return failedPrecondition(fmt::format("{}: cannot read its size", path));
  }
  for (const char* name : {"NumberOfPoints", "NumberOfCells", "NumberOfVerts", "NumberOfLines",
                           "NumberOfStrips", "NumberOfPolys"}) {
    const std::string key = std::string(name) + "=\"";
    for (std::size_t at = head.find(key); at != std::string::npos; at = head.find(key, at + 1)) {
      const char* first = head.data() + at + key.size();
      std::uint64_t count = 0;
      const auto [end, parsed] = std::from_chars(first, head.data() + head.size(), count);
      const std::uint64_t bytesEach = std::string_view(name) == "NumberOfPoints" ? 12 : 4;
      const bool beyond = parsed == std::errc::result_out_of_range ||
                          (parsed == std::errc() && count / kMaxExpansion > fileBytes / bytesEach);
      if (beyond) {
        return failedPrecondition(fmt::format(
            "{}: the header declares {}=\"{}\", more than a file of {} bytes can hold "
            "(truncated or corrupt?)",
            path, name,
            std::string(first, static_cast<std::size_t>(std::min<std::ptrdiff_t>(end - first, 24))),
            fileBytes));
      }
    }
  }
  return Status::ok();
}

// One break the JCFpm crack recorder logged: its iteration and type
// (1 tensile, 2 shear).
struct CrackRecord {
  std::int64_t iteration = 0;
  int type = 0;
  dem::Vec3 at;  // the contact point
};

Result<std::vector<CrackRecord>> readCracks(const std::string& path) {
  auto input = TextInput::open(path);
  if (!input) {
    return input.status();
  }
  std::vector<CrackRecord> cracks;
  std::string line;
  while (input->next(line)) {
    const auto tokens = splitTokens(line);
    if (tokens.empty() || tokens[0] == "iter" || tokens[0].front() == '#') {
      continue;
    }
    if (tokens.size() < 12) {
      return input->error(fmt::format(
          "{} values, expected 12 (iter time p0 p1 p2 type size norm0 norm1 norm2 nrg onJnt)",
          tokens.size()));
    }
    CrackRecord crack;
    double type = 0.0;
    if (!parseId(tokens[0], crack.iteration) || !parseNumber(tokens[5], type) ||
        !parseNumber(tokens[2], crack.at.x) || !parseNumber(tokens[3], crack.at.y) ||
        !parseNumber(tokens[4], crack.at.z)) {
      return input->error("iter, p0, p1, p2 and type must be numbers");
    }
    crack.type = static_cast<int>(type);
    cracks.push_back(crack);
  }
  return cracks;
}

// Exact coordinates as a hash key: the two files print the same doubles.
struct PointKey {
  double x, y, z;
  bool operator==(const PointKey& o) const { return std::memcmp(this, &o, sizeof(PointKey)) == 0; }
};
struct PointKeyHash {
  std::size_t operator()(const PointKey& k) const {
    std::uint64_t h = 1469598103934665603ull;
    for (double v : {k.x, k.y, k.z}) {
      std::uint64_t bits;
      std::memcpy(&bits, &v, 8);
      h = (h ^ bits) * 1099511628211ull;
    }
    return static_cast<std::size_t>(h);
  }
};

class YadeSource final : public StepSource {
 public:
  YadeSource() { m_description.code = "Yade"; }
  const SourceDescription& description() const override { return m_description; }
  int stepCount() const override { return static_cast<int>(m_records.size()); }
  std::int64_t sourceStepNumber(int index) const override {
    return std::next(m_records.begin(), index)->first;
  }
  Result<SourceStep> readStep(int index) override;
  Status add(const std::string& path);
  Status finish();

 private:
  Status readSpheres(const std::string& path, SourceStep& out) const;
  Status readInteractions(const std::string& path, SourceStep& out) const;
  void addCrackCounts(SourceStep& out, std::int64_t previous) const;

  struct Record {
    std::string spheres;
    std::string interactions;
  };
  SourceDescription m_description;
  std::map<std::int64_t, Record> m_records;
  std::map<std::string, int> m_skipped;  // files of other VTKRecorder recorders, by recorder
  std::vector<CrackRecord> m_cracks;
  bool m_withCracks = false;
};

Status YadeSource::add(const std::string& path) {
  const std::string name = baseName(path);
  if (auto recorder = otherRecorder(path)) {
    ++m_skipped[*recorder];
    return Status::ok();
  }
  if (auto spheres = parseRecordName(path, "spheres.", ".vtu")) {
    Record& record = m_records[spheres->iteration];
    if (!record.spheres.empty()) {
      return failedPrecondition(fmt::format("{}: iteration {} has two sphere files ({} and {})",
                                            path, spheres->iteration, baseName(record.spheres),
                                            name));
    }
    record.spheres = path;
  } else if (auto intrs = parseRecordName(path, "intrs.", ".vtp")) {
    Record& record = m_records[intrs->iteration];
    if (!record.interactions.empty()) {
      return failedPrecondition(
          fmt::format("{}: iteration {} has two interaction files ({} and {})", path,
                      intrs->iteration, baseName(record.interactions), name));
    }
    record.interactions = path;
  } else if (name.rfind("cracks_", 0) == 0 && name.size() > 4 &&
             name.compare(name.size() - 4, 4, ".txt") == 0) {
    auto cracks = readCracks(path);
    if (!cracks) {
      return cracks.status();
    }
    m_cracks.insert(m_cracks.end(), cracks->begin(), cracks->end());
    m_withCracks = true;
  } else {
    return invalidArgument(fmt::format(
        "{}: not a Yade VTKRecorder file (spheres.<iter>.vtu, intrs.<iter>.vtp) or JCFpm crack "
        "file (cracks_<Key>.txt)",
        path));
  }
  m_description.files.push_back(path);
  return Status::ok();
}

Status YadeSource::finish() {
  for (const auto& [recorder, files] : m_skipped) {
    m_description.notes.push_back(fmt::format(
        "skipped {} file{} of VTKRecorder's '{}' recorder ({}.<iter>.vt?): crackvis reads spheres "
        "and intrs, and makes its own crack surfaces",
        files, files == 1 ? "" : "s", recorder, recorder));
  }
  if (m_records.empty()) {
    return notFound(
        "no Yade VTKRecorder output among the inputs (recorders=['spheres','id','intr','jcfpm'] "
        "writes spheres.<iter>.vtu and intrs.<iter>.vtp)");
  }
  for (const auto& [iteration, record] : m_records) {
    if (record.spheres.empty()) {
      return failedPrecondition(fmt::format("iteration {}: {} has no spheres.{}.vtu beside it",
                                            iteration, record.interactions, iteration));
    }
    if (record.interactions.empty()) {
      return failedPrecondition(
          fmt::format("iteration {}: {} has no intrs.{}.vtp beside it (record with 'intr')",
                      iteration, record.spheres, iteration));
    }
  }
  return Status::ok();
}

Status YadeSource::readSpheres(const std::string& path, SourceStep& out) const {
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  if (reader->CanReadFile(path.c_str()) == 0) {
    return failedPrecondition(fmt::format("{}: not a readable VTK unstructured grid (.vtu)", path));
  }
  CRACKVIS_RETURN_IF_ERROR(checkDeclaredCounts(path));
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkUnstructuredGrid* grid = reader->GetOutput();
  if (reader->GetErrorCode() != 0 || grid == nullptr || grid->GetPoints() == nullptr) {
    return Status(StatusCode::kFailedPrecondition,
                  fmt::format("{}: cannot read the spheres (truncated or corrupt file)", path));
  }
  const vtkIdType n = grid->GetNumberOfPoints();
  vtkPointData* data = grid->GetPointData();
  vtkDataArray* radii = data->GetArray("radii");
  if (radii == nullptr || radii->GetNumberOfTuples() != n) {
    return failedPrecondition(fmt::format(
        "{}: no 'radii' point array (VTKRecorder's 'spheres' recorder writes it)", path));
  }
  vtkDataArray* ids = data->GetArray("id");
  vtkDataArray* velocity = data->GetArray("linVelVec");
  vtkDataArray* mask = data->GetArray("mask");
  out.ids.resize(static_cast<std::size_t>(n));
  out.positions.resize(static_cast<std::size_t>(n));
  out.radius.resize(static_cast<std::size_t>(n));
  for (vtkIdType i = 0; i < n; ++i) {
    const auto row = static_cast<std::size_t>(i);
    double p[3];
    grid->GetPoint(i, p);
    out.positions[row] = {p[0], p[1], p[2]};
    out.radius[row] = radii->GetComponent(i, 0);
    // Without the 'id' recorder the row is the id: body order, stable
    // while no body is erased.
    const double id = ids != nullptr ? ids->GetComponent(i, 0) : static_cast<double>(i);
    if (id != std::floor(id) || std::abs(id) > 9e15) {
      return failedPrecondition(
          fmt::format("{}: sphere {} has id {}, not an integer", path, i, id));
    }
    out.ids[row] = static_cast<std::int64_t>(id);
  }
  if (velocity != nullptr && velocity->GetNumberOfComponents() == 3) {
    out.velocities.resize(static_cast<std::size_t>(n));
    for (vtkIdType i = 0; i < n; ++i) {
      out.velocities[static_cast<std::size_t>(i)] = {
          static_cast<float>(velocity->GetComponent(i, 0)),
          static_cast<float>(velocity->GetComponent(i, 1)),
          static_cast<float>(velocity->GetComponent(i, 2))};
    }
  }
  if (mask != nullptr) {
    out.group.resize(static_cast<std::size_t>(n));
    for (vtkIdType i = 0; i < n; ++i) {
      out.group[static_cast<std::size_t>(i)] = static_cast<std::int32_t>(mask->GetComponent(i, 0));
    }
  }
  for (int a = 0; a < data->GetNumberOfArrays(); ++a) {
    vtkDataArray* array = data->GetArray(a);
    if (array == nullptr || array == radii || array == ids || array == velocity || array == mask ||
        array->GetNumberOfTuples() != n ||
        (array->GetNumberOfComponents() != 1 && array->GetNumberOfComponents() != 3)) {
      continue;
    }
    dem::ExtraArray extra{safeName(array->GetName() != nullptr ? array->GetName() : "unnamed"),
                          dem::ExtraOwner::kParticles,
                          array->GetNumberOfComponents(),
                          {}};
    extra.values.reserve(static_cast<std::size_t>(n * extra.components));
    for (vtkIdType i = 0; i < n; ++i) {
      for (int c = 0; c < extra.components; ++c) {
        extra.values.push_back(array->GetComponent(i, c));
      }
    }
    out.extras.push_back(std::move(extra));
  }
  return Status::ok();
}

Status YadeSource::readInteractions(const std::string& path, SourceStep& out) const {
  vtkNew<vtkXMLPolyDataReader> reader;
  if (reader->CanReadFile(path.c_str()) == 0) {
    return failedPrecondition(fmt::format("{}: not a readable VTK poly data file (.vtp)", path));
  }
  CRACKVIS_RETURN_IF_ERROR(checkDeclaredCounts(path));
  reader->SetFileName(path.c_str());
  reader->Update();
  vtkPolyData* poly = reader->GetOutput();
  if (reader->GetErrorCode() != 0 || poly == nullptr) {
    return Status(
        StatusCode::kFailedPrecondition,
        fmt::format("{}: cannot read the interactions (truncated or corrupt file)", path));
  }
  std::unordered_map<PointKey, std::int64_t, PointKeyHash> idAt;
  idAt.reserve(out.ids.size());
  for (std::size_t i = 0; i < out.ids.size(); ++i) {
    const dem::Vec3 p = out.positions[i];
    if (!idAt.emplace(PointKey{p.x, p.y, p.z}, out.ids[i]).second) {
      return failedPrecondition(fmt::format(
          "{}: two spheres at the same position ({}, {}, {}): interactions cannot be matched", path,
          p.x, p.y, p.z));
    }
  }
  vtkCellData* data = poly->GetCellData();
  vtkDataArray* cohesive = data->GetArray("isCohesive");
  vtkDataArray* forceN = data->GetArray("forceN");
  dem::ExtraArray normalForce{"forceN", dem::ExtraOwner::kBonds, 1, {}};
  vtkCellArray* lines = poly->GetLines();
  const vtkIdType cells = poly->GetNumberOfCells();
  if (lines == nullptr || (cohesive != nullptr && cohesive->GetNumberOfTuples() != cells)) {
    return failedPrecondition(
        fmt::format("{}: interaction arrays do not match its {} lines", path, cells));
  }
  vtkNew<vtkIdList> ends;
  for (vtkIdType cell = 0; cell < cells; ++cell) {
    poly->GetCellPoints(cell, ends);
    if (ends->GetNumberOfIds() != 2) {
      continue;
    }
    double a[3];
    double b[3];
    poly->GetPoint(ends->GetId(0), a);
    poly->GetPoint(ends->GetId(1), b);
    const auto first = idAt.find(PointKey{a[0], a[1], a[2]});
    const auto second = idAt.find(PointKey{b[0], b[1], b[2]});
    if (first == idAt.end() || second == idAt.end()) {
      continue;  // an interaction with a body that is not a recorded sphere
    }
    SourceBond bond{first->second, second->second, true};
    if (cohesive != nullptr) {
      bond.cohesive = cohesive->GetComponent(cell, 0) != 0.0;
    }
    out.bonds.push_back(bond);
    if (forceN != nullptr) {
      normalForce.values.push_back(forceN->GetComponent(cell, 0));
    }
  }
  if (forceN != nullptr) {
    out.extras.push_back(std::move(normalForce));
  }
  return Status::ok();
}

// The JCFpm crack recorder's count of breaks up to this iteration, as step
// scalars: the code's own record beside the bonds the importer saw break.
// The breaks logged since the previous record go with the step, for the
// importer to give each bond it sees break its recorded mode.
void YadeSource::addCrackCounts(SourceStep& out, std::int64_t previous) const {
  if (!m_withCracks) {
    return;
  }
  out.recordsBreaks = true;
  double all = 0.0;
  double tensile = 0.0;
  double shear = 0.0;
  for (const CrackRecord& crack : m_cracks) {
    if (crack.iteration <= out.sourceStep) {
      all += 1.0;
      tensile += crack.type == 1 ? 1.0 : 0.0;
      shear += crack.type == 2 ? 1.0 : 0.0;
    }
    if (crack.iteration > previous && crack.iteration <= out.sourceStep &&
        (crack.type == 1 || crack.type == 2)) {
      out.breaks.push_back({crack.at, crack.type == 1 ? RecordedBreak::Mode::kTension
                                                      : RecordedBreak::Mode::kShear});
    }
  }
  out.scalars.push_back({"jcfpm_cracks", all});
  out.scalars.push_back({"jcfpm_tensile_cracks", tensile});
  out.scalars.push_back({"jcfpm_shear_cracks", shear});
}

Result<SourceStep> YadeSource::readStep(int index) {
  const auto& [iteration, record] = *std::next(m_records.begin(), index);
  SourceStep out;
  out.sourceStep = iteration;
  out.origin = fmt::format("{} + {}", record.spheres, baseName(record.interactions));
  CRACKVIS_RETURN_IF_ERROR(readSpheres(record.spheres, out));
  CRACKVIS_RETURN_IF_ERROR(readInteractions(record.interactions, out));
  const std::int64_t previous = index > 0 ? std::next(m_records.begin(), index - 1)->first
                                          : std::numeric_limits<std::int64_t>::min();
  addCrackCounts(out, previous);
  return out;
}

}  // namespace

Result<std::unique_ptr<StepSource>> openYade(const std::vector<std::string>& inputs) {
  // VTK's readers report problems on stderr; the importer reports them
  // itself, once, naming the file.
  vtkObject::GlobalWarningDisplayOff();
  auto source = std::make_unique<YadeSource>();
  auto recorded = [](const std::string& file) {
    const std::string name = baseName(file);
    return parseRecordName(file, "spheres.", ".vtu") || parseRecordName(file, "intrs.", ".vtp") ||
           (name.rfind("cracks_", 0) == 0 && name.ends_with(".txt")) || otherRecorder(file);
  };
  CRACKVIS_RETURN_IF_ERROR(
      addInputs(inputs, recorded, [&](const std::string& file) { return source->add(file); }));
  CRACKVIS_RETURN_IF_ERROR(source->finish());
  return std::unique_ptr<StepSource>(std::move(source));
}

}  // namespace crackvis::importers
