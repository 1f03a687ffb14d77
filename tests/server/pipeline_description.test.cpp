#include <filesystem>
#include <fstream>

#include <catch2/catch.hpp>

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
