#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <catch2/catch.hpp>
#include <fmt/format.h>

#include "support/process.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/pipeline/pipeline_description.hpp>

using namespace crackvis;
using namespace crackvis::pipeline;

namespace {

std::string slurp(const std::filesystem::path& path) {
  std::ifstream in(path);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string document(const std::string& body) {
  return "<?xml version=\"1.0\"?>\n<pipeline version=\"1\">\n" + body + "</pipeline>\n";
}

constexpr double kInfinity = std::numeric_limits<double>::infinity();

}  // namespace

TEST_CASE("every example in pipeline-schemas/examples is valid and round-trips", "[pipeline]") {
  int examples = 0;
  for (const auto& entry : std::filesystem::directory_iterator(CRACKVIS_PIPELINE_EXAMPLES)) {
    INFO(entry.path().string());
    auto parsed = parsePipeline(slurp(entry.path()));
    REQUIRE(parsed.isOk());
    auto again = parsePipeline(toXml(*parsed));
    REQUIRE(again.isOk());
    CHECK(*again == *parsed);
    ++examples;
  }
  CHECK(examples >= 3);
}

TEST_CASE("the struct's defaults are the schema's defaults", "[pipeline]") {
  auto minimal = parsePipeline(document("  <data file=\"plate2d.h5\"/>\n"));
  REQUIRE(minimal.isOk());
  PipelineDescription expected;
  expected.file = "plate2d.h5";
  CHECK(*minimal == expected);
  // Elements present without attributes get the same defaults.
  auto spelled = parsePipeline(document(
      "  <data file=\"plate2d.h5\"/>\n  <particles/>\n  <cracks/>\n  <bonds/>\n  <decomposition/>\n"
      "  <inconsistent/>\n  <view/>\n  <stream/>\n"));
  REQUIRE(spelled.isOk());
  CHECK(*spelled == expected);
}

TEST_CASE("the example's values arrive in the description", "[pipeline]") {
  auto parsed = parsePipeline(
      slurp(std::filesystem::path(CRACKVIS_PIPELINE_EXAMPLES) / "cracks-local-voronoi.xml"));
  REQUIRE(parsed.isOk());
  CHECK(parsed->file == "cuboidA.h5");
  CHECK(parsed->step == 199);
  CHECK(parsed->particles.colourBy == ParticleColourBy::kDisplacement);
  CHECK(parsed->particles.opacity == 0.3);
  REQUIRE(parsed->particles.clip.has_value());
  CHECK(parsed->particles.clip->normal == Vec3{0, 1, 0});
  CHECK(parsed->cracks.method == cracks::Method::kLocalVoronoi);
  CHECK(parsed->cracks.colourBy == CrackColourBy::kBreakStep);
  CHECK(parsed->showInconsistent);
  CHECK(parsed->view.background == Colour{0x1e, 0x1e, 0x28});
}

TEST_CASE("a description built in code survives toXml and parse", "[pipeline]") {
  PipelineDescription d;
  d.file = "runs/a&b <1>.h5";
  d.step = 42;
  d.particles.visible = false;
  d.particles.representation = ParticleRepresentation::kPoints;
  d.cracks.method = cracks::Method::kCellCentre;
  d.cracks.mergeOctahedra = true;
  d.cracks.validationTolerance = 0.25;
  d.cracks.decomposition = cracks::Decomposition::kTriangulation;
  d.cracks.largest = 3;
  d.cracks.minComponent = 2.5e-7;
  d.cracks.colourBy = CrackColourBy::kComponent;
  d.bonds.show = BondSelection::kAll;
  d.bonds.representation = BondRepresentation::kTubes;
  d.bonds.colour = Colour{1, 2, 3};
  d.showDecomposition = true;
  d.view.width = 1920;
  d.view.height = 1080;
  d.view.colourMap = ColourMap::kGrayscale;
  d.view.camera = CameraDescription{{1.5, -2, 0.25}, {0.1, 0.05, 0.05}, {0, 0, 1}, 42.5};
  d.stream.fps = 60;
  d.stream.bitrate = 12'000'000;
  auto parsed = parsePipeline(toXml(d));
  REQUIRE(parsed.isOk());
  CHECK(*parsed == d);
}

TEST_CASE("colour ranges, clips, thresholds and annotations survive toXml and parse",
          "[pipeline]") {
  PipelineDescription d;
  d.file = "a.h5";
  d.particles.colourBy = ParticleColourBy::kDisplacement;
  d.particles.range = {RangeMode::kSeries};
  d.particles.threshold =
      Threshold<ParticleColourBy>{ParticleColourBy::kExtra, "damage", 0.25, kInfinity};
  d.cracks.colourBy = CrackColourBy::kBreakStep;
  d.cracks.range = {RangeMode::kUser, -1.5, 2e-3};
  d.cracks.clip = ClipPlane{{0.1, 0.2, 0.3}, {0, 1, 0}};
  d.cracks.threshold = Threshold<CrackColourBy>{CrackColourBy::kForce, "", -kInfinity, 7.5};
  d.bonds.show = BondSelection::kBroken;
  d.bonds.clip = ClipPlane{{0, 0, 0}, {1, 0, 0}};
  d.bonds.threshold = Threshold<BondColourBy>{BondColourBy::kBreakStep, "", 10, 20};
  d.annotations = {true, false, true, false, true};
  const std::string xml = toXml(d);
  auto parsed = parsePipeline(xml);
  REQUIRE(parsed.isOk());
  CHECK(*parsed == d);
  // Open ends are left out, not written as infinities.
  CHECK(xml.find("inf") == std::string::npos);
  // A document without them gets step ranges, no clip or threshold, all annotations.
  auto plain =
      parsePipeline(document("  <data file=\"a.h5\"/>\n  <annotations show=\"false\"/>\n"));
  REQUIRE(plain.isOk());
  CHECK(plain->cracks.range.mode == RangeMode::kStep);
  CHECK_FALSE(plain->bonds.clip);
  CHECK_FALSE(plain->particles.threshold);
  CHECK_FALSE(plain->annotations.show);
  CHECK(plain->annotations.scaleBar);
}

TEST_CASE("a saved view's client layout survives toXml and parse, a bad one is refused",
          "[pipeline]") {
  PipelineDescription d;
  d.file = "a.h5";
  d.clientLayout = "AAAA/+09bGF5b3V0=";
  auto parsed = parsePipeline(toXml(d));
  REQUIRE(parsed.isOk());
  CHECK(parsed->clientLayout == d.clientLayout);
  CHECK(toXml(PipelineDescription{}).find("<client") == std::string::npos);
  auto bad = parsePipeline(document("  <data file=\"a.h5\"/>\n  <client layout=\"a<b\"/>\n"));
  CHECK_FALSE(bad.isOk());
  auto quoted =
      parsePipeline(document("  <data file=\"a.h5\"/>\n  <client layout=\"x&quot;y\"/>\n"));
  REQUIRE_FALSE(quoted.isOk());
  CHECK_THAT(quoted.status().message(), Catch::Contains("client"));
}

TEST_CASE("particles colour by a file's extra array: extra:NAME", "[pipeline]") {
  auto parsed = parsePipeline(
      document("  <data file=\"a.h5\"/>\n  <particles colour-by=\"extra:damage\"/>\n"));
  REQUIRE(parsed);
  CHECK(parsed->particles.colourBy == ParticleColourBy::kExtra);
  CHECK(parsed->particles.colourByExtra == "damage");
  auto again = parsePipeline(toXml(*parsed));
  REQUIRE(again);
  CHECK(*again == *parsed);
  CHECK_THAT(toXml(*parsed), Catch::Contains("colour-by=\"extra:damage\""));
  auto bonds = parsePipeline(
      document("  <data file=\"a.h5\"/>\n  <bonds show=\"all\" colour-by=\"extra:forceN\"/>\n"));
  REQUIRE(bonds);
  CHECK(bonds->bonds.colourBy == BondColourBy::kExtra);
  CHECK(bonds->bonds.colourByExtra == "forceN");
  CHECK(*parsePipeline(toXml(*bonds)) == *bonds);
}

TEST_CASE("invalid documents are refused naming the line and the element",
          "[pipeline][validation]") {
  struct Case {
    const char* name;
    std::string xml;
    std::vector<std::string> parts;
  };
  const std::vector<Case> cases{
      {"not well-formed",
       "<?xml version=\"1.0\"?>\n<pipeline version=\"1\">\n  <data file=\"a.h5\">\n</pipeline>\n",
       {"pipeline line 5: not well-formed XML", "Premature end of data in tag pipeline line 2"}},
      {"empty", "", {"not well-formed XML"}},
      {"unknown method",
       document("  <data file=\"a.h5\"/>\n  <cracks method=\"marching-cubes\"/>\n"),
       {"pipeline line 4, element <cracks>", "marching-cubes"}},
      {"missing file",
       document("  <data step=\"3\"/>\n"),
       {"line 3, element <data>", "'file' is required"}},
      {"opacity out of range",
       document("  <data file=\"a.h5\"/>\n  <particles opacity=\"1.5\"/>\n"),
       {"line 4, element <particles>", "1.5"}},
      {"unknown element",
       document("  <data file=\"a.h5\"/>\n  <lights/>\n"),
       {"line 4, element <lights>"}},
      {"elements out of order",
       document("  <view/>\n  <data file=\"a.h5\"/>\n"),
       {"element <view>"}},
      {"no data", document("  <view/>\n"), {"element <view>"}},
      {"an extra array name with a path in it",
       document("  <data file=\"a.h5\"/>\n  <particles colour-by=\"extra:../x\"/>\n"),
       {"line 4, element <particles>", "extra:../x"}},
      {"an extra array without a name",
       document("  <data file=\"a.h5\"/>\n  <particles colour-by=\"extra:\"/>\n"),
       {"line 4, element <particles>"}},
      {"wrong version",
       "<pipeline version=\"2\"><data file=\"a.h5\"/></pipeline>",
       {"line 1, element <pipeline>", "'2'"}},
      {"vector of two",
       document("  <data file=\"a.h5\"/>\n  <particles>\n    <clip origin=\"0 0\" normal=\"1 0 "
                "0\"/>\n  </particles>\n"),
       {"line 5, element <clip>", "origin"}},
      {"colour by name",
       document("  <data file=\"a.h5\"/>\n  <cracks colour=\"red\"/>\n"),
       {"line 4, element <cracks>", "red"}},
      {"step below -1 (the last)",
       document("  <data file=\"a.h5\" step=\"-2\"/>\n"),
       {"line 3, element <data>", "-2"}},
      {"frame size",
       document("  <data file=\"a.h5\"/>\n  <view width=\"99999\"/>\n"),
       {"line 4, element <view>", "99999"}},
      {"external entity",
       "<?xml version=\"1.0\"?>\n<!DOCTYPE pipeline [<!ENTITY secret SYSTEM "
       "\"file:///etc/passwd\">]>\n"
       "<pipeline version=\"1\"><data file=\"&secret;\"/></pipeline>\n",
       {"not well-formed XML", "external entity 'secret'"}},
      {"harmless DOCTYPE",
       "<?xml version=\"1.0\"?>\n<!DOCTYPE pipeline [<!ENTITY name \"a.h5\">]>\n"
       "<pipeline version=\"1\"><data file=\"&name;\"/></pipeline>\n",
       {"a DOCTYPE is not allowed"}},
  };
  for (const Case& c : cases) {
    DYNAMIC_SECTION(c.name) {
      auto parsed = parsePipeline(c.xml);
      REQUIRE_FALSE(parsed.isOk());
      CHECK(parsed.status().code() == StatusCode::kInvalidArgument);
      for (const std::string& part : c.parts) {
        CHECK_THAT(parsed.status().message(), Catch::Contains(part));
      }
      CHECK(parsed.status().message().find('\n') == std::string::npos);
    }
  }
}

TEST_CASE("an oversized document is refused before parsing", "[pipeline][validation]") {
  const std::string huge =
      document("  <data file=\"" + std::string(kMaxPipelineBytes, 'a') + "\"/>\n");
  auto parsed = parsePipeline(huge);
  REQUIRE_FALSE(parsed.isOk());
  CHECK_THAT(parsed.status().message(), Catch::Contains("the limit is 1048576"));
}

namespace {

// Documents under the size limit built to make a parser or validator work
// harder than their size: many attributes on one element (80,000 took 93 s
// of CPU before the schema refused it), many elements, deep nesting, many
// comments, namespace declarations, character references.
std::vector<std::pair<std::string, std::string>> costlyDocuments() {
  auto attributes = [](int count, const char* prefix) {
    std::string out;
    for (int i = 0; i < count; ++i) {
      out += fmt::format(" {}{}=\"1\"", prefix, i);
    }
    return out;
  };
  auto repeated = [](int count, const std::string& piece) {
    std::string out;
    for (int i = 0; i < count; ++i) {
      out += piece;
    }
    return out;
  };
  return {
      {"80,000 attributes", document("  <data file=\"a.h5\"" + attributes(80'000, "a") + "/>\n")},
      {"20,000 attributes", document("  <data file=\"a.h5\"" + attributes(20'000, "x") + "/>\n")},
      {"namespace declarations",
       document("  <data file=\"a.h5\"" + attributes(40'000, "xmlns:n") + "/>\n")},
      {"100,000 elements", document("  <data file=\"a.h5\"/>\n" + repeated(100'000, "<x/>"))},
      {"deep nesting",
       document("  <data file=\"a.h5\"/>\n" + repeated(60'000, "<x>") + repeated(60'000, "</x>"))},
      {"50,000 comments",
       document("  <data file=\"a.h5\"/>\n" + repeated(50'000, "<!-- <x a='1'> -->"))},
      {"character references",
       document("  <data file=\"" + repeated(100'000, "&#x41;") + "\"/>\n")},
      {"a long valid name", document("  <data file=\"" + std::string(1'000'000, 'a') + "\"/>\n")},
  };
}

}  // namespace

TEST_CASE("a document under the size limit is refused or accepted within 100 ms",
          "[pipeline][validation]") {
  for (const auto& [what, xml] : costlyDocuments()) {
    INFO(what << " (" << xml.size() << " bytes)");
    REQUIRE(xml.size() <= kMaxPipelineBytes);
    double fastest = 1e9;
    Status status;
    for (int run = 0; run < 3; ++run) {  // the fastest of three: a busy machine is not the parser
      const auto start = std::chrono::steady_clock::now();
      status = parsePipeline(xml).status();
      fastest = std::min(
          fastest, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    INFO(status.message() << ", fastest of 3: " << fastest * 1e3 << " ms");
    CHECK(fastest < 0.1);
    if (!status.isOk()) {
      CHECK(status.code() == StatusCode::kInvalidArgument);
      CHECK(status.message().find('\n') == std::string::npos);
    }
  }
}

TEST_CASE("a document with more attributes or elements than a pipeline holds names the count",
          "[pipeline][validation]") {
  const auto documents = costlyDocuments();
  const Status attributes = parsePipeline(documents[1].second).status();
  CHECK_THAT(attributes.message(),
             Catch::StartsWith("pipeline line 3: an element with 20001 attributes"));
  const Status elements = parsePipeline(documents[3].second).status();
  CHECK_THAT(elements.message(), Catch::Contains("100002 elements"));
  // '<' and '=' inside quoted values and comments count for nothing.
  std::string quoted = document("  <!-- " + std::string(200, '<') + "a=1 -->\n" +
                                "  <data file=\"a" + std::string(100, '=') + ".h5\"/>\n");
  CHECK(parsePipeline(quoted).isOk());
}

#include "pipeline/bad_attributes.hpp"

using crackvis::testing::BadAttribute;
using crackvis::testing::badAttributes;

TEST_CASE("every numeric attribute is converted with range checks", "[pipeline][validation]") {
  for (const BadAttribute& bad : badAttributes()) {
    DYNAMIC_SECTION(bad.name) {
      auto parsed = parsePipeline(bad.xml);
      REQUIRE_FALSE(parsed.isOk());
      CHECK(parsed.status().code() == StatusCode::kInvalidArgument);
      const std::string& message = parsed.status().message();
      CHECK_THAT(message, Catch::StartsWith("pipeline " + bad.where));
      CHECK_THAT(message, Catch::Contains("attribute '" + bad.attribute + "'"));
      CHECK_THAT(message, Catch::Contains(bad.value));
      CHECK(message.find('\n') == std::string::npos);
    }
  }
}

TEST_CASE("numbers in every spelling the schema allows are read exactly",
          "[pipeline][validation]") {
  auto parsed = parsePipeline(document(
      "  <data file=\"a.h5\" step=\"+2147483647\"/>\n"
      "  <particles opacity=\" 5e-1 \">\n"
      "    <clip origin=\"-0 1E2  3.\" normal=\"0 0 -4.9e-324\"/>\n  </particles>\n"
      "  <cracks validation-tolerance=\"1\" opacity=\"0\"/>\n  <bonds tube-radius=\"1e-300\"/>\n"
      "  <view width=\"16\" height=\"7680\">\n"
      "    <camera position=\"1 2 3\" focal-point=\"0 0 0\" view-angle=\"179.5\"/>\n  </view>\n"
      "  <stream fps=\"120\" bitrate=\"100000000\"/>\n"));
  INFO(parsed.status().message());
  REQUIRE(parsed.isOk());
  CHECK(parsed->step == 2147483647);
  CHECK(parsed->particles.opacity == 0.5);
  REQUIRE(parsed->particles.clip.has_value());
  CHECK(parsed->particles.clip->origin == Vec3{0, 100, 3});
  CHECK(parsed->particles.clip->normal.z == -4.9e-324);
  CHECK(parsed->cracks.validationTolerance == 1.0);
  CHECK(parsed->bonds.tubeRadius == 1e-300);
  CHECK(parsed->view.width == 16);
  CHECK(parsed->view.height == 7680);
  REQUIRE(parsed->view.camera.has_value());
  CHECK(parsed->view.camera->viewAngle == 179.5);
  CHECK(parsed->stream.fps == 120);
  CHECK(parsed->stream.bitrate == 100'000'000);
  // And back: toXml writes what parses to the same values.
  auto again = parsePipeline(toXml(*parsed));
  REQUIRE(again.isOk());
  CHECK(*again == *parsed);
}

TEST_CASE("a long bad value is echoed shortened", "[pipeline][validation]") {
  const std::string digits(5000, '9');
  auto parsed = parsePipeline(document("  <data file=\"a.h5\" step=\"" + digits + "\"/>\n"));
  REQUIRE_FALSE(parsed.isOk());
  CHECK_THAT(parsed.status().message(), Catch::Contains("attribute 'step'"));
  CHECK(parsed.status().message().size() < 400);
}
