#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <memory>

#include <fmt/format.h>
#include <libxml/parser.h>
#include <libxml/tree.h>
#include <libxml/xmlschemas.h>

#include "pipeline_schema_text.hpp"
#include <crackvis/pipeline/pipeline_description.hpp>
#include <crackvis/vocabulary/names.hpp>

namespace crackvis::pipeline {
namespace {

// Enumerations and their spellings in the schema, in one place each.
template <typename E, std::size_t N>
using Names = std::array<std::pair<E, const char*>, N>;

constexpr Names<ParticleRepresentation, 2> kParticleRepresentations{
    {{ParticleRepresentation::kImpostors, "impostors"},
     {ParticleRepresentation::kPoints, "points"}}};
constexpr Names<ParticleColourBy, 6> kParticleColourBy{
    {{ParticleColourBy::kSolid, "solid"},
     {ParticleColourBy::kRadius, "radius"},
     {ParticleColourBy::kDisplacement, "displacement"},
     {ParticleColourBy::kVelocity, "velocity"},
     {ParticleColourBy::kDamage, "damage"},
     {ParticleColourBy::kFragment, "fragment"}}};
constexpr Names<cracks::Decomposition, 3> kDecompositions{
    {{cracks::Decomposition::kAuto, "auto"},
     {cracks::Decomposition::kLattice, "lattice"},
     {cracks::Decomposition::kTriangulation, "triangulation"}}};
constexpr Names<CrackColourBy, 8> kCrackColourBy{{{CrackColourBy::kSolid, "solid"},
                                                  {CrackColourBy::kBondId, "bond-id"},
                                                  {CrackColourBy::kForce, "force"},
                                                  {CrackColourBy::kBreakStep, "break-step"},
                                                  {CrackColourBy::kState, "state"},
                                                  {CrackColourBy::kComponent, "component"},
                                                  {CrackColourBy::kOpening, "opening"},
                                                  {CrackColourBy::kSlip, "slip"}}};
constexpr Names<BondSelection, 3> kBondSelections{{{BondSelection::kNone, "none"},
                                                   {BondSelection::kBroken, "broken"},
                                                   {BondSelection::kAll, "all"}}};
constexpr Names<BondRepresentation, 2> kBondRepresentations{
    {{BondRepresentation::kLines, "lines"}, {BondRepresentation::kTubes, "tubes"}}};
constexpr Names<BondColourBy, 4> kBondColourBy{{{BondColourBy::kSolid, "solid"},
                                                {BondColourBy::kState, "state"},
                                                {BondColourBy::kForce, "force"},
                                                {BondColourBy::kBreakStep, "break-step"}}};
constexpr Names<ColourMap, 4> kColourMaps{{{ColourMap::kViridis, "viridis"},
                                           {ColourMap::kCoolWarm, "cool-warm"},
                                           {ColourMap::kRainbow, "rainbow"},
                                           {ColourMap::kGrayscale, "grayscale"}}};
constexpr Names<RangeMode, 3> kRangeModes{
    {{RangeMode::kStep, "step"}, {RangeMode::kSeries, "series"}, {RangeMode::kUser, "user"}}};

template <typename E, std::size_t N>
const char* nameOf(const Names<E, N>& names, E value) {
  for (const auto& [v, name] : names) {
    if (v == value) {
      return name;
    }
  }
  return names[0].second;
}

struct DocFree {
  void operator()(xmlDoc* doc) const { xmlFreeDoc(doc); }
};
struct ParserFree {
  void operator()(xmlParserCtxt* context) const { xmlFreeParserCtxt(context); }
};
struct ValidFree {
  void operator()(xmlSchemaValidCtxt* context) const { xmlSchemaFreeValidCtxt(context); }
};

// What an error echoes of a value: attributes may be long, messages are not.
std::string echoed(std::string_view text, std::size_t limit = 40) {
  return text.size() <= limit
             ? std::string(text)
             : fmt::format("{}... ({} characters)", text.substr(0, limit), text.size());
}

// libxml2's message, one line, the values it quotes shortened with it.
std::string trimmed(const char* message) {
  std::string_view text = message != nullptr ? message : "";
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) {
    text.remove_suffix(1);
  }
  std::string line = echoed(text, 300);
  std::replace(line.begin(), line.end(), '\n', ' ');
  return line;
}

// The schema, parsed once; validation contexts are per call, so parsing
// documents from several sessions at once is safe.
xmlSchema* schema() {
  static xmlSchema* parsed = [] {
    xmlInitParser();
    const std::string_view text = pipelineSchema();
    xmlSchemaParserCtxt* context =
        xmlSchemaNewMemParserCtxt(text.data(), static_cast<int>(text.size()));
    xmlSchema* result = xmlSchemaParse(context);
    xmlSchemaFreeParserCtxt(context);
    return result;
  }();
  return parsed;
}

struct FirstError {
  std::string text;
};

void keepFirstError(void* data, xmlError* error) {
  auto* first = static_cast<FirstError*>(data);
  if (!first->text.empty() || error == nullptr) {
    return;
  }
  const auto* node = static_cast<const xmlNode*>(error->node);
  const std::string element =
      node != nullptr && node->name != nullptr ? reinterpret_cast<const char*>(node->name) : "?";
  const int line = node != nullptr && node->line > 0 ? node->line : error->line;
  first->text =
      fmt::format("pipeline line {}, element <{}>: {}", line, element, trimmed(error->message));
}

bool named(const xmlNode* node, const char* name) {
  return node->type == XML_ELEMENT_NODE &&
         xmlStrcmp(node->name, reinterpret_cast<const xmlChar*>(name)) == 0;
}

const xmlNode* child(const xmlNode* node, const char* name) {
  for (const xmlNode* c = node->children; c != nullptr; c = c->next) {
    if (named(c, name)) {
      return c;
    }
  }
  return nullptr;
}

// XML Schema's whitespace (the "collapse" facet of numbers and lists).
bool isXmlSpace(char ch) {
  return ch == ' ' || ch == '\t' || ch == '\n' || ch == '\r';
}

std::string_view stripped(std::string_view text) {
  while (!text.empty() && isXmlSpace(text.front())) {
    text.remove_prefix(1);
  }
  while (!text.empty() && isXmlSpace(text.back())) {
    text.remove_suffix(1);
  }
  return text;
}

// A number's text without the leading '+' that XML Schema allows and
// std::from_chars does not; a second sign is left in place to be refused.
std::string_view withoutPlus(std::string_view text) {
  if (text.size() > 1 && text.front() == '+' && text[1] != '-' && text[1] != '+') {
    text.remove_prefix(1);
  }
  return text;
}

// The range of a real attribute; open ends exclude their bound.
struct Interval {
  double min;
  double max;
  bool minOpen = false;
  bool maxOpen = false;

  bool contains(double v) const {
    return (minOpen ? v > min : v >= min) && (maxOpen ? v < max : v <= max);
  }
  std::string text() const {
    return fmt::format("{}{} .. {}{}", minOpen ? "(" : "[", min, max, maxOpen ? ")" : "]");
  }
};

constexpr Interval kUnitInterval{0.0, 1.0};
constexpr Interval kTubeRadius{0.0, 1.0, true, false};
constexpr Interval kViewAngle{0.0, 180.0, true, true};
constexpr double kLargest = std::numeric_limits<double>::max();
constexpr Interval kCoordinate{-kLargest, kLargest};

// The range of an integer attribute, both ends included.
struct Span {
  std::int64_t min;
  std::int64_t max;
};

// Steps are int indices downstream; a wider value must not wrap.
constexpr Span kStep{-1, std::numeric_limits<int>::max()};
constexpr Span kPixels{16, 7680};
constexpr Span kFps{1, 120};
constexpr Span kBitrate{100'000, 100'000'000};
constexpr Span kVersion{1, 1};
constexpr Span kComponents{0, 1'000'000};
constexpr Interval kArea{0.0, kLargest};

// The attributes of one element, converted with range checks: every value
// of a description passes through these few functions. The first error is
// kept (naming line, element and attribute) and the caller asks status()
// once per element; after an error the readers return harmless defaults.
class Attributes {
 public:
  explicit Attributes(const xmlNode* node) : m_node(node) {}

  std::string text(const char* name) {
    xmlChar* value = xmlGetProp(m_node, reinterpret_cast<const xmlChar*>(name));
    if (value == nullptr) {
      fail(name, "is missing");
      return {};
    }
    std::string result = reinterpret_cast<const char*>(value);
    xmlFree(value);
    return result;
  }

  std::int64_t integer(const char* name, Span span) {
    const std::string raw = text(name);
    const std::string_view digits = withoutPlus(stripped(raw));
    std::int64_t value = 0;
    const auto [end, error] = std::from_chars(digits.data(), digits.data() + digits.size(), value);
    if (error == std::errc::invalid_argument || end != digits.data() + digits.size()) {
      fail(name, fmt::format("'{}' is not an integer", echoed(raw)));
      return span.min;
    }
    if (error == std::errc::result_out_of_range || value < span.min || value > span.max) {
      fail(name, fmt::format("'{}' is out of range ({} .. {})", echoed(raw), span.min, span.max));
      return span.min;
    }
    return value;
  }

  double real(const char* name, Interval interval) {
    const std::string raw = text(name);
    return realIn(name, raw, stripped(raw), interval);
  }

  // An attribute without a default: nullopt when absent.
  std::optional<double> optionalReal(const char* name, Interval interval) {
    if (xmlHasProp(m_node, reinterpret_cast<const xmlChar*>(name)) == nullptr) {
      return std::nullopt;
    }
    return real(name, interval);
  }

  // Three finite numbers; `nonZero` refuses the zero vector (a direction).
  Vec3 vector(const char* name, bool nonZero = false) {
    const std::string raw = text(name);
    std::array<double, 3> xyz{};
    std::string_view rest = raw;
    std::size_t count = 0;
    while (m_status.isOk()) {
      rest = stripped(rest);
      if (rest.empty()) {
        break;
      }
      std::size_t length = 0;
      while (length < rest.size() && !isXmlSpace(rest[length])) {
        ++length;
      }
      if (count < xyz.size()) {
        xyz[count] = realIn(name, raw, rest.substr(0, length), kCoordinate);
      }
      ++count;
      rest.remove_prefix(length);
    }
    if (m_status.isOk() && count != xyz.size()) {
      fail(name, fmt::format("'{}' is not three numbers", echoed(raw)));
    }
    const Vec3 v{xyz[0], xyz[1], xyz[2]};
    if (m_status.isOk() && nonZero && v.x == 0.0 && v.y == 0.0 && v.z == 0.0) {
      fail(name, "is the zero vector, a direction is needed");
    }
    return v;
  }

  Colour colour(const char* name) {
    const std::string raw = text(name);
    const auto hex = [&](std::size_t at) {
      unsigned value = 0;
      const char* first = raw.data() + at;
      const auto [end, error] = std::from_chars(first, first + 2, value, 16);
      return error == std::errc{} && end == first + 2 ? static_cast<int>(value) : -1;
    };
    if (raw.size() == 7 && raw[0] == '#') {
      const int r = hex(1), g = hex(3), b = hex(5);
      if (r >= 0 && g >= 0 && b >= 0) {
        return Colour{static_cast<std::uint8_t>(r), static_cast<std::uint8_t>(g),
                      static_cast<std::uint8_t>(b)};
      }
    }
    fail(name, fmt::format("'{}' is not a colour #rrggbb", echoed(raw)));
    return {};
  }

  bool boolean(const char* name) {
    const std::string raw = text(name);
    const std::string_view value = stripped(raw);
    if (value == "true" || value == "1") {
      return true;
    }
    if (value != "false" && value != "0") {
      fail(name, fmt::format("'{}' is not a boolean", echoed(raw)));
    }
    return false;
  }

  template <typename E, std::size_t N>
  E choice(const char* name, const Names<E, N>& names) {
    const std::string raw = text(name);
    for (const auto& [v, spelling] : names) {
      if (raw == spelling) {
        return v;
      }
    }
    fail(name, fmt::format("'{}' is not one of the allowed values", echoed(raw)));
    return names[0].first;
  }

  // A built-in quantity or "extra:NAME" (NAME as crackvis-dem names extras),
  // which gives `extraValue` and the name in `extra`.
  template <typename E, std::size_t N>
  E choiceOrExtra(const char* name, const Names<E, N>& names, E extraValue, std::string& extra) {
    const std::string raw = text(name);
    constexpr std::string_view kPrefix = "extra:";
    if (raw.rfind(kPrefix, 0) != 0) {
      return choice(name, names);
    }
    extra = raw.substr(kPrefix.size());
    if (Status valid = dem::validateName("extra array", extra); !valid) {
      fail(name, fmt::format("'{}': {}", echoed(raw), valid.message()));
    }
    return extraValue;
  }

  cracks::Method method(const char* name) {
    auto method = cracks::parseMethod(text(name));
    if (!method) {
      fail(name, method.status().message());
      return cracks::Method::kLocalVoronoi;
    }
    return *method;
  }

  const Status& status() const { return m_status; }

  // An error about `name` beyond its own value (an attribute it needs).
  void fail(const char* name, const std::string& what) {
    if (m_status.isOk()) {
      m_status = invalidArgument(
          fmt::format("pipeline line {}, element <{}>, attribute '{}': {}", xmlGetLineNo(m_node),
                      reinterpret_cast<const char*>(m_node->name), name, what));
    }
  }

 private:
  double realIn(const char* name, const std::string& raw, std::string_view number,
                Interval interval) {
    number = withoutPlus(number);
    double value = 0.0;
    const auto [end, error] = std::from_chars(number.data(), number.data() + number.size(), value);
    if (error == std::errc::result_out_of_range) {
      fail(name, fmt::format("'{}' is out of the range of a double", echoed(raw)));
      return 0.0;
    }
    if (error != std::errc{} || end != number.data() + number.size() || number.empty()) {
      fail(name, fmt::format("'{}' is not a number", echoed(raw)));
      return 0.0;
    }
    if (!std::isfinite(value)) {
      fail(name, fmt::format("'{}' is not a finite number", echoed(raw)));
      return 0.0;
    }
    if (!interval.contains(value)) {
      fail(name, fmt::format("'{}' is out of range {}", echoed(raw), interval.text()));
      return 0.0;
    }
    return value;
  }

  const xmlNode* m_node;
  Status m_status;
};

// range, range-min and range-max of a coloured layer.
ColourRange colourRange(Attributes& a) {
  ColourRange range;
  range.mode = a.choice("range", kRangeModes);
  const auto min = a.optionalReal("range-min", kCoordinate);
  const auto max = a.optionalReal("range-max", kCoordinate);
  if (range.mode != RangeMode::kUser) {
    return range;
  }
  if (!min || !max) {
    a.fail(min ? "range-max" : "range-min", "is required with range=\"user\"");
  } else if (*min >= *max) {
    a.fail("range-max", fmt::format("{} is not above range-min {}", *max, *min));
  } else {
    range.min = *min;
    range.max = *max;
  }
  return range;
}

// The optional <clip> child of a layer.
Status convertClip(const xmlNode* layer, std::optional<ClipPlane>& clip) {
  if (const xmlNode* node = child(layer, "clip")) {
    Attributes c(node);
    clip = ClipPlane{c.vector("origin"), c.vector("normal", true)};
    return c.status();
  }
  return Status::ok();
}

// The optional <threshold> child of a layer: a quantity of it, not solid,
// and at least one finite end.
template <typename E, std::size_t N>
Status convertThreshold(const xmlNode* layer, const Names<E, N>& names, E extraValue,
                        std::optional<Threshold<E>>& threshold) {
  const xmlNode* node = child(layer, "threshold");
  if (node == nullptr) {
    return Status::ok();
  }
  Attributes a(node);
  Threshold<E> t;
  t.by = a.choiceOrExtra("by", names, extraValue, t.byExtra);
  const auto min = a.optionalReal("min", kCoordinate);
  const auto max = a.optionalReal("max", kCoordinate);
  if (a.status().isOk() && t.by == names[0].first) {  // solid
    a.fail("by", "'solid' is no quantity to threshold by");
  } else if (a.status().isOk() && !min && !max) {
    a.fail("min", "a threshold needs min, max or both");
  } else if (min && max && *min > *max) {
    a.fail("max", fmt::format("{} is below min {}", *max, *min));
  }
  t.min = min.value_or(t.min);
  t.max = max.value_or(t.max);
  CRACKVIS_RETURN_IF_ERROR(a.status());
  threshold = t;
  return Status::ok();
}

// A layer reads one extra array: a threshold on extra:A beside colour-by
// extra:B is refused.
template <typename E>
Status checkOneExtraArray(const xmlNode* layer, const char* layerName,
                          const std::optional<Threshold<E>>& threshold, E colourBy,
                          const std::string& colourByExtra, E extraValue) {
  if (threshold && threshold->by == extraValue && colourBy == extraValue &&
      threshold->byExtra != colourByExtra) {
    return invalidArgument(fmt::format(
        "pipeline line {}, element <threshold>, attribute 'by': extra:{} differs from the {}' "
        "colour-by extra:{} (one extra array per layer)",
        xmlGetLineNo(child(layer, "threshold")), threshold->byExtra, layerName, colourByExtra));
  }
  return Status::ok();
}

// Crack quantities have no extra arrays: a value no spelling gives.
constexpr auto kNoCrackExtra = static_cast<CrackColourBy>(-1);

Status convertData(const xmlNode* node, PipelineDescription& d) {
  Attributes a(node);
  d.file = a.text("file");
  d.step = a.integer("step", kStep);
  if (a.status().isOk() && d.file.empty()) {
    return invalidArgument(fmt::format(
        "pipeline line {}, element <data>, attribute 'file': is empty", xmlGetLineNo(node)));
  }
  return a.status();
}

Status convertParticles(const xmlNode* node, ParticlesDescription& p) {
  Attributes a(node);
  p.visible = a.boolean("visible");
  p.representation = a.choice("representation", kParticleRepresentations);
  p.colourBy =
      a.choiceOrExtra("colour-by", kParticleColourBy, ParticleColourBy::kExtra, p.colourByExtra);
  p.colour = a.colour("colour");
  p.opacity = a.real("opacity", kUnitInterval);
  p.range = colourRange(a);
  CRACKVIS_RETURN_IF_ERROR(a.status());
  CRACKVIS_RETURN_IF_ERROR(convertClip(node, p.clip));
  CRACKVIS_RETURN_IF_ERROR(
      convertThreshold(node, kParticleColourBy, ParticleColourBy::kExtra, p.threshold));
  // A source reads one per-particle extra array: the one coloured by, or
  // else the one thresholded by.
  return checkOneExtraArray(node, "particles", p.threshold, p.colourBy, p.colourByExtra,
                            ParticleColourBy::kExtra);
}

Status convertCracks(const xmlNode* node, CracksDescription& c) {
  Attributes a(node);
  c.visible = a.boolean("visible");
  c.method = a.method("method");
  c.validation = a.boolean("validation");
  c.validationTolerance = a.real("validation-tolerance", kUnitInterval);
  c.mergeOctahedra = a.boolean("merge-octahedra");
  c.decomposition = a.choice("decomposition", kDecompositions);
  c.largest = static_cast<int>(a.integer("largest", kComponents));
  c.minComponent = a.real("min-component", kArea);
  c.colourBy = a.choice("colour-by", kCrackColourBy);
  c.colour = a.colour("colour");
  c.opacity = a.real("opacity", kUnitInterval);
  c.range = colourRange(a);
  CRACKVIS_RETURN_IF_ERROR(a.status());
  CRACKVIS_RETURN_IF_ERROR(convertClip(node, c.clip));
  return convertThreshold(node, kCrackColourBy, kNoCrackExtra, c.threshold);
}

Status convertBonds(const xmlNode* node, BondsDescription& b) {
  Attributes a(node);
  b.show = a.choice("show", kBondSelections);
  b.representation = a.choice("representation", kBondRepresentations);
  b.colourBy = a.choiceOrExtra("colour-by", kBondColourBy, BondColourBy::kExtra, b.colourByExtra);
  b.colour = a.colour("colour");
  b.tubeRadius = a.real("tube-radius", kTubeRadius);
  b.range = colourRange(a);
  CRACKVIS_RETURN_IF_ERROR(a.status());
  CRACKVIS_RETURN_IF_ERROR(convertClip(node, b.clip));
  CRACKVIS_RETURN_IF_ERROR(
      convertThreshold(node, kBondColourBy, BondColourBy::kExtra, b.threshold));
  return checkOneExtraArray(node, "bonds", b.threshold, b.colourBy, b.colourByExtra,
                            BondColourBy::kExtra);
}

Status convertView(const xmlNode* node, ViewDescription& v) {
  Attributes a(node);
  v.width = static_cast<int>(a.integer("width", kPixels));
  v.height = static_cast<int>(a.integer("height", kPixels));
  v.background = a.colour("background");
  v.colourMap = a.choice("colour-map", kColourMaps);
  v.scalarBar = a.boolean("scalar-bar");
  CRACKVIS_RETURN_IF_ERROR(a.status());
  if (const xmlNode* camera = child(node, "camera")) {
    Attributes c(camera);
    v.camera = CameraDescription{c.vector("position"), c.vector("focal-point"),
                                 c.vector("view-up", true), c.real("view-angle", kViewAngle)};
    CRACKVIS_RETURN_IF_ERROR(c.status());
    if (v.camera->position == v.camera->focalPoint) {
      return invalidArgument(fmt::format(
          "pipeline line {}, element <camera>, attribute 'focal-point': equals the position",
          xmlGetLineNo(camera)));
    }
  }
  return Status::ok();
}

Status convertToggle(const xmlNode* node, bool& show) {
  Attributes a(node);
  show = a.boolean("show");
  return a.status();
}

Status convertAnnotations(const xmlNode* node, AnnotationsDescription& n) {
  Attributes a(node);
  n.show = a.boolean("show");
  n.time = a.boolean("time");
  n.method = a.boolean("method");
  n.axes = a.boolean("axes");
  n.scaleBar = a.boolean("scale-bar");
  return a.status();
}

Status convertStream(const xmlNode* node, StreamDescription& s) {
  Attributes a(node);
  s.fps = static_cast<int>(a.integer("fps", kFps));
  s.bitrate = static_cast<int>(a.integer("bitrate", kBitrate));
  return a.status();
}

// Reads a validated document; the schema filled in every default attribute.
// The schema already bounds most values, but the conversions check again:
// the schema's xs:double admits INF, NaN and values a double cannot hold.
Result<PipelineDescription> convert(const xmlNode* root) {
  PipelineDescription d;
  Attributes pipeline(root);
  pipeline.integer("version", kVersion);
  CRACKVIS_RETURN_IF_ERROR(pipeline.status());
  for (const xmlNode* node = root->children; node != nullptr; node = node->next) {
    Status status;
    if (named(node, "data")) {
      status = convertData(node, d);
    } else if (named(node, "particles")) {
      status = convertParticles(node, d.particles);
    } else if (named(node, "cracks")) {
      status = convertCracks(node, d.cracks);
    } else if (named(node, "bonds")) {
      status = convertBonds(node, d.bonds);
    } else if (named(node, "decomposition")) {
      status = convertToggle(node, d.showDecomposition);
    } else if (named(node, "inconsistent")) {
      status = convertToggle(node, d.showInconsistent);
    } else if (named(node, "view")) {
      status = convertView(node, d.view);
    } else if (named(node, "annotations")) {
      status = convertAnnotations(node, d.annotations);
    } else if (named(node, "stream")) {
      status = convertStream(node, d.stream);
    } else if (named(node, "client")) {
      Attributes a(node);
      d.clientLayout = a.text("layout");
      status = a.status();
    }
    CRACKVIS_RETURN_IF_ERROR(status);
  }
  return d;
}

std::string hex(Colour c) {
  return fmt::format("#{:02x}{:02x}{:02x}", c.r, c.g, c.b);
}
std::string text(Vec3 v) {
  return fmt::format("{} {} {}", v.x, v.y, v.z);
}
const char* text(bool value) {
  return value ? "true" : "false";
}

std::string escaped(const std::string& raw) {
  std::string out;
  for (char ch : raw) {
    switch (ch) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += ch;
    }
  }
  return out;
}

// How many elements and attributes a document holds, counted on its raw
// text before libxml2 sees it. libxml2's duplicate-attribute check and the
// schema validator cost time that grows faster than the document (80,000
// made-up attributes on one element, 0.87 MB, took 93 s), so a document
// that cannot be a pipeline by its counts alone is refused in one linear
// pass. Comments, CDATA sections and processing instructions are skipped;
// a '<' or '=' in an attribute value is inside quotes and not counted.
struct DocumentShape {
  std::size_t elements = 0;
  std::size_t mostAttributes = 0;  // on any one element
  std::size_t line = 0;            // where that element starts
};

DocumentShape shapeOf(std::string_view xml) {
  DocumentShape shape;
  std::size_t line = 1;
  std::size_t i = 0;
  auto skipPast = [&](std::string_view end) {
    const std::size_t found = xml.find(end, i);
    const std::size_t stop = found == std::string_view::npos ? xml.size() : found + end.size();
    line += static_cast<std::size_t>(std::count(xml.begin() + i, xml.begin() + stop, '\n'));
    i = stop;
  };
  while (i < xml.size()) {
    const char ch = xml[i];
    if (ch == '\n') {
      ++line;
    }
    if (ch != '<') {
      ++i;
      continue;
    }
    const std::string_view rest = xml.substr(i);
    if (rest.substr(0, 4) == "<!--") {
      skipPast("-->");
    } else if (rest.substr(0, 9) == "<![CDATA[") {
      skipPast("]]>");
    } else if (rest.substr(0, 2) == "<?") {
      skipPast("?>");
    } else if (rest.size() > 1 && rest[1] != '/' && rest[1] != '!') {
      ++shape.elements;
      const std::size_t start = line;
      std::size_t attributes = 0;
      char quote = 0;
      for (++i; i < xml.size() && (quote != 0 || xml[i] != '>'); ++i) {
        const char c = xml[i];
        line += c == '\n' ? 1 : 0;
        if (quote != 0) {
          quote = c == quote ? 0 : quote;
        } else if (c == '"' || c == '\'') {
          quote = c;
        } else if (c == '=') {
          ++attributes;
        }
      }
      if (attributes > shape.mostAttributes) {
        shape.mostAttributes = attributes;
        shape.line = start;
      }
    } else {
      ++i;
    }
  }
  return shape;
}

// A valid pipeline has at most 19 elements (one of each, clips and
// thresholds on three layers, a camera) and 14 attributes on one element;
// the limits leave room for namespace declarations.
constexpr std::size_t kMaxPipelineElements = 64;
constexpr std::size_t kMaxPipelineAttributes = 64;

Status checkShape(std::string_view xml) {
  const DocumentShape shape = shapeOf(xml);
  if (shape.elements > kMaxPipelineElements) {
    return invalidArgument(
        fmt::format("pipeline: {} elements, more than a pipeline description can hold ({})",
                    shape.elements, kMaxPipelineElements));
  }
  if (shape.mostAttributes > kMaxPipelineAttributes) {
    return invalidArgument(fmt::format(
        "pipeline line {}: an element with {} attributes, more than any pipeline element has "
        "({} at most)",
        shape.line, shape.mostAttributes, kMaxPipelineAttributes));
  }
  return Status::ok();
}

}  // namespace

std::string_view pipelineSchema() {
  return kPipelineSchemaText;
}

Result<PipelineDescription> parsePipeline(std::string_view xml) {
  if (xml.size() > kMaxPipelineBytes) {
    return invalidArgument(fmt::format("pipeline document of {} bytes, the limit is {}", xml.size(),
                                       kMaxPipelineBytes));
  }
  CRACKVIS_RETURN_IF_ERROR(checkShape(xml));
  xmlSchema* compiled = schema();
  if (compiled == nullptr) {
    return internalError("the built-in pipeline schema does not parse");
  }
  std::unique_ptr<xmlParserCtxt, ParserFree> parser(xmlNewParserCtxt());
  // No network, no entity expansion beyond the predefined ones, no DTD loads.
  std::unique_ptr<xmlDoc, DocFree> doc(xmlCtxtReadMemory(
      parser.get(), xml.data(), static_cast<int>(xml.size()), "pipeline.xml", nullptr,
      XML_PARSE_NONET | XML_PARSE_NOERROR | XML_PARSE_NOWARNING | XML_PARSE_NOBLANKS));
  if (doc == nullptr) {
    const xmlError* error = xmlCtxtGetLastError(parser.get());
    return invalidArgument(
        fmt::format("pipeline line {}: not well-formed XML: {}", error != nullptr ? error->line : 0,
                    trimmed(error != nullptr ? error->message : "empty document")));
  }
  // A DOCTYPE could declare entities (external files, entity expansion
  // bombs); descriptions have no use for one.
  if (doc->intSubset != nullptr || doc->extSubset != nullptr) {
    return invalidArgument("pipeline: a DOCTYPE is not allowed in pipeline documents");
  }
  std::unique_ptr<xmlSchemaValidCtxt, ValidFree> validator(xmlSchemaNewValidCtxt(compiled));
  FirstError first;
  xmlSchemaSetValidStructuredErrors(validator.get(), keepFirstError, &first);
  // Adds the schema's default attributes to the tree, so defaults live only there.
  xmlSchemaSetValidOptions(validator.get(), XML_SCHEMA_VAL_VC_I_CREATE);
  if (xmlSchemaValidateDoc(validator.get(), doc.get()) != 0) {
    return invalidArgument(first.text.empty() ? "pipeline: does not match the schema" : first.text);
  }
  return convert(xmlDocGetRootElement(doc.get()));
}

// The colour-by attribute's text: a built-in name or extra:NAME.
template <typename E, std::size_t N>
std::string colourByText(const Names<E, N>& names, E value, E extraValue,
                         const std::string& extra) {
  return value == extraValue ? "extra:" + escaped(extra) : std::string(nameOf(names, value));
}

// range="..." and, for a user range, its ends.
std::string rangeText(const ColourRange& r) {
  std::string out = fmt::format(" range=\"{}\"", nameOf(kRangeModes, r.mode));
  if (r.mode == RangeMode::kUser) {
    out += fmt::format(" range-min=\"{}\" range-max=\"{}\"", r.min, r.max);
  }
  return out;
}

// A layer's <clip> and <threshold> children, closing the element either way.
template <typename E, std::size_t N>
std::string layerChildren(const char* element, const std::optional<ClipPlane>& clip,
                          const std::optional<Threshold<E>>& threshold, const Names<E, N>& names,
                          E extraValue) {
  if (!clip && !threshold) {
    return "/>\n";
  }
  std::string out = ">\n";
  if (clip) {
    out += fmt::format("    <clip origin=\"{}\" normal=\"{}\"/>\n", text(clip->origin),
                       text(clip->normal));
  }
  if (threshold) {
    out += fmt::format("    <threshold by=\"{}\"",
                       colourByText(names, threshold->by, extraValue, threshold->byExtra));
    if (std::isfinite(threshold->min)) {
      out += fmt::format(" min=\"{}\"", threshold->min);
    }
    if (std::isfinite(threshold->max)) {
      out += fmt::format(" max=\"{}\"", threshold->max);
    }
    out += "/>\n";
  }
  return out + fmt::format("  </{}>\n", element);
}

std::string toXml(const PipelineDescription& d) {
  std::string out = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<pipeline version=\"1\">\n";
  out += fmt::format("  <data file=\"{}\" step=\"{}\"/>\n", escaped(d.file), d.step);
  const auto& p = d.particles;
  out += fmt::format(
      "  <particles visible=\"{}\" representation=\"{}\" colour-by=\"{}\" colour=\"{}\" "
      "opacity=\"{}\"{}",
      text(p.visible), nameOf(kParticleRepresentations, p.representation),
      colourByText(kParticleColourBy, p.colourBy, ParticleColourBy::kExtra, p.colourByExtra),
      hex(p.colour), p.opacity, rangeText(p.range));
  out +=
      layerChildren("particles", p.clip, p.threshold, kParticleColourBy, ParticleColourBy::kExtra);
  const auto& c = d.cracks;
  out += fmt::format(
      "  <cracks visible=\"{}\" method=\"{}\" validation=\"{}\" validation-tolerance=\"{}\" "
      "merge-octahedra=\"{}\" decomposition=\"{}\" largest=\"{}\" min-component=\"{}\" "
      "colour-by=\"{}\" colour=\"{}\" opacity=\"{}\"{}",
      text(c.visible), cracks::toString(c.method), text(c.validation), c.validationTolerance,
      text(c.mergeOctahedra), nameOf(kDecompositions, c.decomposition), c.largest, c.minComponent,
      nameOf(kCrackColourBy, c.colourBy), hex(c.colour), c.opacity, rangeText(c.range));
  out += layerChildren("cracks", c.clip, c.threshold, kCrackColourBy, kNoCrackExtra);
  const auto& b = d.bonds;
  out += fmt::format(
      "  <bonds show=\"{}\" representation=\"{}\" colour-by=\"{}\" colour=\"{}\" "
      "tube-radius=\"{}\"{}",
      nameOf(kBondSelections, b.show), nameOf(kBondRepresentations, b.representation),
      colourByText(kBondColourBy, b.colourBy, BondColourBy::kExtra, b.colourByExtra), hex(b.colour),
      b.tubeRadius, rangeText(b.range));
  out += layerChildren("bonds", b.clip, b.threshold, kBondColourBy, BondColourBy::kExtra);
  out += fmt::format("  <decomposition show=\"{}\"/>\n", text(d.showDecomposition));
  out += fmt::format("  <inconsistent show=\"{}\"/>\n", text(d.showInconsistent));
  const auto& v = d.view;
  out += fmt::format(
      "  <view width=\"{}\" height=\"{}\" background=\"{}\" colour-map=\"{}\" scalar-bar=\"{}\"",
      v.width, v.height, hex(v.background), nameOf(kColourMaps, v.colourMap), text(v.scalarBar));
  if (v.camera) {
    out += fmt::format(
        ">\n    <camera position=\"{}\" focal-point=\"{}\" view-up=\"{}\" view-angle=\"{}\"/>\n  "
        "</view>\n",
        text(v.camera->position), text(v.camera->focalPoint), text(v.camera->viewUp),
        v.camera->viewAngle);
  } else {
    out += "/>\n";
  }
  const auto& n = d.annotations;
  out += fmt::format(
      "  <annotations show=\"{}\" time=\"{}\" method=\"{}\" axes=\"{}\" scale-bar=\"{}\"/>\n",
      text(n.show), text(n.time), text(n.method), text(n.axes), text(n.scaleBar));
  out += fmt::format("  <stream fps=\"{}\" bitrate=\"{}\"/>\n", d.stream.fps, d.stream.bitrate);
  if (!d.clientLayout.empty()) {  // base64: nothing to escape
    out += fmt::format("  <client layout=\"{}\"/>\n", d.clientLayout);
  }
  out += "</pipeline>\n";
  return out;
}

}  // namespace crackvis::pipeline
