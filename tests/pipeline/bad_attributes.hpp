// Pipeline documents that each hold one bad numeric attribute, and what the
// refusal must name: shared by the parser's tests and crackvis-render's
// command line test (tests/scene/snapshot.test.cpp).
#pragma once

#include <limits>
#include <string>
#include <vector>

namespace crackvis::testing {

inline std::string pipelineDocument(const std::string& body) {
  return "<?xml version=\"1.0\"?>\n<pipeline version=\"1\">\n" + body + "</pipeline>\n";
}

// A document whose line 4 is `line` (after <data> on line 3).
inline std::string withLine(const std::string& line) {
  return pipelineDocument("  <data file=\"a.h5\"/>\n" + line + "\n");
}

// Every numeric attribute with values the schema's types admit or that only
// the conversions catch: beyond a double (1e-400, 1e309), beyond 64 or 32
// bits, NaN and infinities, zero directions. Each must be refused naming
// the line, the element and the attribute, never thrown.
struct BadAttribute {
  const char* name;
  std::string xml;
  std::string where;  // "line N, element <e>"
  std::string attribute;
  std::string value;
};

inline std::vector<BadAttribute> badAttributes() {
  return {
      {"step beyond 64 bits",
       pipelineDocument("  <data file=\"a.h5\" step=\"99999999999999999999\"/>\n"),
       "line 3, element <data>", "step", "99999999999999999999"},
      {"step beyond an int", pipelineDocument("  <data file=\"a.h5\" step=\"2147483648\"/>\n"),
       "line 3, element <data>", "step", "2147483648"},
      {"step not an integer", pipelineDocument("  <data file=\"a.h5\" step=\"1.5\"/>\n"),
       "line 3, element <data>", "step", "1.5"},
      {"particle opacity below a double", withLine("  <particles opacity=\"1e-400\"/>"),
       "line 4, element <particles>", "opacity", "1e-400"},
      {"particle opacity NaN", withLine("  <particles opacity=\"NaN\"/>"),
       "line 4, element <particles>", "opacity", "NaN"},
      {"particle opacity negative", withLine("  <particles opacity=\"-0.5\"/>"),
       "line 4, element <particles>", "opacity", "-0.5"},
      {"clip origin beyond a double",
       withLine("  <particles>\n    <clip origin=\"1e309 0 0\" normal=\"0 1 0\"/>\n  </particles>"),
       "line 5, element <clip>", "origin", "1e309"},
      {"clip origin infinite",
       withLine("  <particles>\n    <clip origin=\"0 INF 0\" normal=\"0 1 0\"/>\n  </particles>"),
       "line 5, element <clip>", "origin", "INF"},
      {"clip normal NaN",
       withLine("  <particles>\n    <clip origin=\"0 0 0\" normal=\"0 NaN 1\"/>\n  </particles>"),
       "line 5, element <clip>", "normal", "NaN"},
      {"clip normal zero",
       withLine("  <particles>\n    <clip origin=\"0 0 0\" normal=\"0 0 0\"/>\n  </particles>"),
       "line 5, element <clip>", "normal", "zero vector"},
      {"largest components negative", withLine("  <cracks largest=\"-1\"/>"),
       "line 4, element <cracks>", "largest", "-1"},
      {"component area negative", withLine("  <cracks min-component=\"-1e-6\"/>"),
       "line 4, element <cracks>", "min-component", "-1e-6"},
      {"decomposition unknown", withLine("  <cracks decomposition=\"voronoi\"/>"),
       "line 4, element <cracks>", "decomposition", "voronoi"},
      {"validation tolerance below a double",
       withLine("  <cracks validation-tolerance=\"1e-400\"/>"), "line 4, element <cracks>",
       "validation-tolerance", "1e-400"},
      {"crack opacity infinite", withLine("  <cracks opacity=\"INF\"/>"),
       "line 4, element <cracks>", "opacity", "INF"},
      {"crack opacity NaN", withLine("  <cracks opacity=\"NaN\"/>"), "line 4, element <cracks>",
       "opacity", "NaN"},
      {"tube radius below a double", withLine("  <bonds tube-radius=\"1e-400\"/>"),
       "line 4, element <bonds>", "tube-radius", "1e-400"},
      {"tube radius zero", withLine("  <bonds tube-radius=\"0\"/>"), "line 4, element <bonds>",
       "tube-radius", "0"},
      {"tube radius NaN", withLine("  <bonds tube-radius=\"NaN\"/>"), "line 4, element <bonds>",
       "tube-radius", "NaN"},
      {"width beyond an int", withLine("  <view width=\"2147483648\"/>"), "line 4, element <view>",
       "width", "2147483648"},
      {"height negative", withLine("  <view height=\"-720\"/>"), "line 4, element <view>", "height",
       "-720"},
      {"height beyond 64 bits", withLine("  <view height=\"99999999999999999999\"/>"),
       "line 4, element <view>", "height", "99999999999999999999"},
      {"camera position beyond a double",
       withLine("  <view>\n    <camera position=\"1 1e999 1\" focal-point=\"0 0 0\"/>\n  </view>"),
       "line 5, element <camera>", "position", "1e999"},
      {"camera focal point NaN",
       withLine("  <view>\n    <camera position=\"1 1 1\" focal-point=\"NaN 0 0\"/>\n  </view>"),
       "line 5, element <camera>", "focal-point", "NaN"},
      {"camera focal point at the position",
       withLine("  <view>\n    <camera position=\"1 1 1\" focal-point=\"1 1 1\"/>\n  </view>"),
       "line 5, element <camera>", "focal-point", "equals the position"},
      {"camera view-up zero",
       withLine("  <view>\n    <camera position=\"1 1 1\" focal-point=\"0 0 0\" view-up=\"0 0 "
                "0\"/>\n  </view>"),
       "line 5, element <camera>", "view-up", "zero vector"},
      {"camera view-up infinite",
       withLine("  <view>\n    <camera position=\"1 1 1\" focal-point=\"0 0 0\" view-up=\"0 0 "
                "-INF\"/>\n  </view>"),
       "line 5, element <camera>", "view-up", "-INF"},
      {"view angle below a double",
       withLine("  <view>\n    <camera position=\"1 1 1\" focal-point=\"0 0 0\" "
                "view-angle=\"1e-400\"/>\n  </view>"),
       "line 5, element <camera>", "view-angle", "1e-400"},
      {"view angle NaN",
       withLine("  <view>\n    <camera position=\"1 1 1\" focal-point=\"0 0 0\" "
                "view-angle=\"NaN\"/>\n  </view>"),
       "line 5, element <camera>", "view-angle", "NaN"},
      {"view angle 180",
       withLine("  <view>\n    <camera position=\"1 1 1\" focal-point=\"0 0 0\" "
                "view-angle=\"180\"/>\n  </view>"),
       "line 5, element <camera>", "view-angle", "180"},
      {"fps beyond 64 bits", withLine("  <stream fps=\"99999999999999999999\"/>"),
       "line 4, element <stream>", "fps", "99999999999999999999"},
      {"fps zero", withLine("  <stream fps=\"0\"/>"), "line 4, element <stream>", "fps", "0"},
      {"bitrate beyond an int", withLine("  <stream bitrate=\"2147483648\"/>"),
       "line 4, element <stream>", "bitrate", "2147483648"},
      {"bitrate negative", withLine("  <stream bitrate=\"-4000000\"/>"), "line 4, element <stream>",
       "bitrate", "-4000000"},
      {"user range without its minimum",
       withLine("  <particles colour-by=\"radius\" range=\"user\" range-max=\"2\"/>"),
       "line 4, element <particles>", "range-min", "is required"},
      {"user range upside down",
       withLine("  <cracks colour-by=\"force\" range=\"user\" range-min=\"5\" range-max=\"1\"/>"),
       "line 4, element <cracks>", "range-max", "not above range-min 5"},
      {"user range infinite",
       withLine("  <bonds range=\"user\" range-min=\"0\" range-max=\"INF\"/>"),
       "line 4, element <bonds>", "range-max", "INF"},
      {"threshold by solid",
       withLine("  <particles>\n    <threshold by=\"solid\" min=\"0\"/>\n  </particles>"),
       "line 5, element <threshold>", "by", "'solid'"},
      {"threshold without ends", withLine("  <bonds>\n    <threshold by=\"force\"/>\n  </bonds>"),
       "line 5, element <threshold>", "min", "needs min, max or both"},
      {"threshold upside down",
       withLine("  <cracks>\n    <threshold by=\"break-step\" min=\"9\" max=\"3\"/>\n  </cracks>"),
       "line 5, element <threshold>", "max", "below min 9"},
      {"threshold NaN",
       withLine("  <cracks>\n    <threshold by=\"force\" min=\"NaN\"/>\n  </cracks>"),
       "line 5, element <threshold>", "min", "NaN"},
      {"threshold on another extra array than the colour",
       withLine("  <particles colour-by=\"extra:a\">\n    <threshold by=\"extra:b\" max=\"1\"/>\n"
                "  </particles>"),
       "line 5, element <threshold>", "by", "extra:b differs"},
      {"crack clip without a direction",
       withLine("  <cracks>\n    <clip origin=\"0 0 0\" normal=\"0 0 0\"/>\n  </cracks>"),
       "line 5, element <clip>", "normal", "zero vector"},
  };
}

}  // namespace crackvis::testing
