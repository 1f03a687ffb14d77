// Pipeline descriptions: what a render session shows and how it streams, as
// an XML document valid against pipeline-schemas/pipeline.xsd (the contract
// between the client and the render server; docs/pipeline.md is the
// reference). parsePipeline validates with libxml2 and returns the typed
// description; toXml writes one back, every attribute explicit.
//
// The struct's defaults are the schema's defaults (a test parses the minimal
// document and compares).
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>

#include <crackvis/common/status.hpp>
#include <crackvis/vocabulary/crack_method.hpp>
#include <crackvis/vocabulary/vec3.hpp>

namespace crackvis::pipeline {

using dem::Vec3;

struct Colour {
  std::uint8_t r = 0;
  std::uint8_t g = 0;
  std::uint8_t b = 0;
  friend bool operator==(const Colour&, const Colour&) = default;
};

enum class ParticleRepresentation { kImpostors, kPoints };
// kExtra: a per-particle extra array of the file, named by colourByExtra.
// kFragment: the rank of the particle's fragment (0 the largest; analysis/).
enum class ParticleColourBy {
  kSolid,
  kRadius,
  kDisplacement,
  kVelocity,
  kDamage,
  kExtra,
  kFragment
};
// kOpening, kSlip: the crack's opening and slip per surface element (analysis/).
enum class CrackColourBy {
  kSolid,
  kBondId,
  kForce,
  kBreakStep,
  kState,
  kComponent,
  kOpening,
  kSlip
};
enum class BondSelection { kNone, kBroken, kAll };
enum class BondRepresentation { kLines, kTubes };
// kExtra: a per-bond extra array of the file, named by colourByExtra.
enum class BondColourBy { kSolid, kState, kForce, kBreakStep, kExtra };
enum class ColourMap { kViridis, kCoolWarm, kRainbow, kGrayscale };

struct ClipPlane {
  Vec3 origin;
  Vec3 normal;
  friend bool operator==(const ClipPlane&, const ClipPlane&) = default;
};

// How a coloured layer's colours span its values: over the step shown (each
// step its own range), over the whole series (every step scanned once, so a
// colour means the same value at every step), or the range the user set.
enum class RangeMode { kStep, kSeries, kUser };
struct ColourRange {
  RangeMode mode = RangeMode::kStep;
  double min = 0.0;  // kUser
  double max = 1.0;  // kUser, > min
  friend bool operator==(const ColourRange&, const ColourRange&) = default;
};

// Keeps only a layer's elements whose value of `by` (a colour-by quantity of
// that layer, not solid) lies in [min, max]; an end not given is infinite.
template <typename By>
struct Threshold {
  By by{};
  std::string byExtra;  // NAME of by="extra:NAME"
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool contains(double v) const { return v >= min && v <= max; }
  friend bool operator==(const Threshold&, const Threshold&) = default;
};

struct ParticlesDescription {
  bool visible = true;
  ParticleRepresentation representation = ParticleRepresentation::kImpostors;
  ParticleColourBy colourBy = ParticleColourBy::kSolid;
  std::string colourByExtra;  // NAME of colour-by="extra:NAME" (kExtra)
  Colour colour{0xb0, 0xb0, 0xb0};
  double opacity = 1.0;
  ColourRange range;
  std::optional<ClipPlane> clip;
  std::optional<Threshold<ParticleColourBy>> threshold;
  friend bool operator==(const ParticlesDescription&, const ParticlesDescription&) = default;
};

struct CracksDescription {
  bool visible = true;
  cracks::Method method = cracks::Method::kLocalVoronoi;
  bool validation = true;
  double validationTolerance = 0.1;
  bool mergeOctahedra = false;
  cracks::Decomposition decomposition = cracks::Decomposition::kAuto;
  int largest = 0;            // keep the K largest components (0: all)
  double minComponent = 0.0;  // and only those of at least this area, m^2
  CrackColourBy colourBy = CrackColourBy::kSolid;
  Colour colour{0xe0, 0x3c, 0x31};
  double opacity = 1.0;
  ColourRange range;
  std::optional<ClipPlane> clip;
  std::optional<Threshold<CrackColourBy>> threshold;
  friend bool operator==(const CracksDescription&, const CracksDescription&) = default;
};

struct BondsDescription {
  BondSelection show = BondSelection::kNone;
  BondRepresentation representation = BondRepresentation::kLines;
  BondColourBy colourBy = BondColourBy::kState;
  std::string colourByExtra;  // NAME of colour-by="extra:NAME" (kExtra)
  Colour colour{0x40, 0x40, 0x40};
  double tubeRadius = 0.15;  // fraction of the particle radius
  ColourRange range;
  std::optional<ClipPlane> clip;
  std::optional<Threshold<BondColourBy>> threshold;
  friend bool operator==(const BondsDescription&, const BondsDescription&) = default;
};

struct CameraDescription {
  Vec3 position;
  Vec3 focalPoint;
  Vec3 viewUp{0, 0, 1};
  double viewAngle = 30.0;  // degrees
  friend bool operator==(const CameraDescription&, const CameraDescription&) = default;
};

struct ViewDescription {
  int width = 1280;
  int height = 720;
  Colour background{0x1e, 0x1e, 0x28};
  ColourMap colourMap = ColourMap::kViridis;
  bool scalarBar = true;
  std::optional<CameraDescription> camera;  // none: reset to show the specimen
  friend bool operator==(const ViewDescription&, const ViewDescription&) = default;
};

// What is written over the picture besides the scalar bars (on by default in
// snapshots, movies and the stream).
struct AnnotationsDescription {
  bool show = true;      // false: none of them
  bool time = true;      // step (of the file's steps) and simulated time
  bool method = true;    // the crack method and its options
  bool axes = true;      // an x, y, z triad turning with the camera
  bool scaleBar = true;  // a length scale in metres at the focal plane
  friend bool operator==(const AnnotationsDescription&, const AnnotationsDescription&) = default;
};

struct StreamDescription {
  int fps = 30;
  int bitrate = 4'000'000;  // bits per second
  friend bool operator==(const StreamDescription&, const StreamDescription&) = default;
};

struct PipelineDescription {
  std::string file;  // under the data service's root
  std::int64_t step = 0;
  ParticlesDescription particles;
  CracksDescription cracks;
  BondsDescription bonds;
  bool showDecomposition = false;
  bool showInconsistent = false;
  ViewDescription view;
  AnnotationsDescription annotations;
  StreamDescription stream;
  // <client layout="...">: crackvis-client's window state (base64, opaque
  // here) in a saved view; empty: none.
  std::string clientLayout;
  friend bool operator==(const PipelineDescription&, const PipelineDescription&) = default;
};

// Documents larger than this are refused before parsing.
inline constexpr std::size_t kMaxPipelineBytes = 1 << 20;

// Validates `xml` against the schema and converts it. INVALID_ARGUMENT naming
// the line and the element for a malformed or invalid document.
Result<PipelineDescription> parsePipeline(std::string_view xml);

// A document valid against the schema that parses back to `description`.
std::string toXml(const PipelineDescription& description);

// The schema's text (pipeline-schemas/pipeline.xsd, built in).
std::string_view pipelineSchema();

}  // namespace crackvis::pipeline
