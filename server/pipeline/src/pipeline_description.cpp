#include <array>
#include <memory>
#include <mutex>
#include <sstream>

#include <fmt/format.h>
#include <libxml/parser.h>
#include <libxml/tree.h>
#include <libxml/xmlschemas.h>

#include "pipeline_schema_text.hpp"
#include <crackvis/pipeline/pipeline_description.hpp>

namespace crackvis::pipeline {
namespace {

// Enumerations and their spellings in the schema, in one place each.
template <typename E, std::size_t N>
using Names = std::array<std::pair<E, const char*>, N>;

constexpr Names<ParticleRepresentation, 2> kParticleRepresentations{
    {{ParticleRepresentation::kImpostors, "impostors"},
     {ParticleRepresentation::kPoints, "points"}}};
constexpr Names<ParticleColourBy, 5> kParticleColourBy{
    {{ParticleColourBy::kSolid, "solid"},
     {ParticleColourBy::kRadius, "radius"},
     {ParticleColourBy::kDisplacement, "displacement"},
     {ParticleColourBy::kVelocity, "velocity"},
     {ParticleColourBy::kDamage, "damage"}}};
constexpr Names<CrackColourBy, 5> kCrackColourBy{{{CrackColourBy::kSolid, "solid"},
                                                  {CrackColourBy::kBondId, "bond-id"},
                                                  {CrackColourBy::kForce, "force"},
                                                  {CrackColourBy::kBreakStep, "break-step"},
                                                  {CrackColourBy::kState, "state"}}};
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

template <typename E, std::size_t N>
const char* nameOf(const Names<E, N>& names, E value) {
  for (const auto& [v, name] : names) {
    if (v == value) {
      return name;
    }
  }
  return names[0].second;
}

template <typename E, std::size_t N>
E valueOf(const Names<E, N>& names, const std::string& text) {
  for (const auto& [v, name] : names) {
    if (text == name) {
      return v;
    }
  }
  return names[0].first;  // unreachable after validation
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

std::string trimmed(const char* message) {
  std::string text = message != nullptr ? message : "";
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) {
    text.pop_back();
  }
  return text;
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

std::string attribute(const xmlNode* node, const char* name) {
  xmlChar* value = xmlGetProp(node, reinterpret_cast<const xmlChar*>(name));
  if (value == nullptr) {
    return {};
  }
  std::string text = reinterpret_cast<const char*>(value);
  xmlFree(value);
  return text;
}

bool boolean(const std::string& text) {
  return text == "true" || text == "1";
}

Vec3 vec3(const std::string& text) {
  std::istringstream in(text);
  Vec3 v;
  in >> v.x >> v.y >> v.z;
  return v;
}

Colour colour(const std::string& text) {
  const auto hex = [&](std::size_t at) {
    return static_cast<std::uint8_t>(std::stoi(text.substr(at, 2), nullptr, 16));
  };
  return text.size() == 7 ? Colour{hex(1), hex(3), hex(5)} : Colour{};
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

// Reads a validated document; the schema filled in every default attribute.
PipelineDescription convert(const xmlNode* root) {
  PipelineDescription d;
  for (const xmlNode* node = root->children; node != nullptr; node = node->next) {
    if (named(node, "data")) {
      d.file = attribute(node, "file");
      d.step = std::stoll(attribute(node, "step"));
    } else if (named(node, "particles")) {
      auto& p = d.particles;
      p.visible = boolean(attribute(node, "visible"));
      p.representation = valueOf(kParticleRepresentations, attribute(node, "representation"));
      p.colourBy = valueOf(kParticleColourBy, attribute(node, "colour-by"));
      p.colour = colour(attribute(node, "colour"));
      p.opacity = std::stod(attribute(node, "opacity"));
      if (const xmlNode* clip = child(node, "clip")) {
        p.clip = ClipPlane{vec3(attribute(clip, "origin")), vec3(attribute(clip, "normal"))};
      }
    } else if (named(node, "cracks")) {
      auto& c = d.cracks;
      c.visible = boolean(attribute(node, "visible"));
      c.method = *cracks::parseMethod(attribute(node, "method"));
      c.validation = boolean(attribute(node, "validation"));
      c.validationTolerance = std::stod(attribute(node, "validation-tolerance"));
      c.mergeOctahedra = boolean(attribute(node, "merge-octahedra"));
      c.colourBy = valueOf(kCrackColourBy, attribute(node, "colour-by"));
      c.colour = colour(attribute(node, "colour"));
      c.opacity = std::stod(attribute(node, "opacity"));
    } else if (named(node, "bonds")) {
      auto& b = d.bonds;
      b.show = valueOf(kBondSelections, attribute(node, "show"));
      b.representation = valueOf(kBondRepresentations, attribute(node, "representation"));
      b.colourBy = valueOf(kBondColourBy, attribute(node, "colour-by"));
      b.colour = colour(attribute(node, "colour"));
      b.tubeRadius = std::stod(attribute(node, "tube-radius"));
    } else if (named(node, "decomposition")) {
      d.showDecomposition = boolean(attribute(node, "show"));
    } else if (named(node, "inconsistent")) {
      d.showInconsistent = boolean(attribute(node, "show"));
    } else if (named(node, "view")) {
      auto& v = d.view;
      v.width = std::stoi(attribute(node, "width"));
      v.height = std::stoi(attribute(node, "height"));
      v.background = colour(attribute(node, "background"));
      v.colourMap = valueOf(kColourMaps, attribute(node, "colour-map"));
      v.scalarBar = boolean(attribute(node, "scalar-bar"));
      if (const xmlNode* camera = child(node, "camera")) {
        v.camera = CameraDescription{
            vec3(attribute(camera, "position")), vec3(attribute(camera, "focal-point")),
            vec3(attribute(camera, "view-up")), std::stod(attribute(camera, "view-angle"))};
      }
    } else if (named(node, "stream")) {
      d.stream.fps = std::stoi(attribute(node, "fps"));
      d.stream.bitrate = std::stoi(attribute(node, "bitrate"));
    }
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

}  // namespace

std::string_view pipelineSchema() {
  return kPipelineSchemaText;
}

Result<PipelineDescription> parsePipeline(std::string_view xml) {
  if (xml.size() > kMaxPipelineBytes) {
    return invalidArgument(fmt::format("pipeline document of {} bytes, the limit is {}", xml.size(),
                                       kMaxPipelineBytes));
  }
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

std::string toXml(const PipelineDescription& d) {
  std::string out = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<pipeline version=\"1\">\n";
  out += fmt::format("  <data file=\"{}\" step=\"{}\"/>\n", escaped(d.file), d.step);
  const auto& p = d.particles;
  out += fmt::format(
      "  <particles visible=\"{}\" representation=\"{}\" colour-by=\"{}\" colour=\"{}\" "
      "opacity=\"{}\"",
      text(p.visible), nameOf(kParticleRepresentations, p.representation),
      nameOf(kParticleColourBy, p.colourBy), hex(p.colour), p.opacity);
  if (p.clip) {
    out += fmt::format(">\n    <clip origin=\"{}\" normal=\"{}\"/>\n  </particles>\n",
                       text(p.clip->origin), text(p.clip->normal));
  } else {
    out += "/>\n";
  }
  const auto& c = d.cracks;
  out += fmt::format(
      "  <cracks visible=\"{}\" method=\"{}\" validation=\"{}\" validation-tolerance=\"{}\" "
      "merge-octahedra=\"{}\" colour-by=\"{}\" colour=\"{}\" opacity=\"{}\"/>\n",
      text(c.visible), cracks::toString(c.method), text(c.validation), c.validationTolerance,
      text(c.mergeOctahedra), nameOf(kCrackColourBy, c.colourBy), hex(c.colour), c.opacity);
  const auto& b = d.bonds;
  out += fmt::format(
      "  <bonds show=\"{}\" representation=\"{}\" colour-by=\"{}\" colour=\"{}\" "
      "tube-radius=\"{}\"/>\n",
      nameOf(kBondSelections, b.show), nameOf(kBondRepresentations, b.representation),
      nameOf(kBondColourBy, b.colourBy), hex(b.colour), b.tubeRadius);
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
  out += fmt::format("  <stream fps=\"{}\" bitrate=\"{}\"/>\n", d.stream.fps, d.stream.bitrate);
  out += "</pipeline>\n";
  return out;
}

}  // namespace crackvis::pipeline
