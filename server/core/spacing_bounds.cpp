// The scale a volume may have (core/volume_io.h: kMinSpacing, kMaxSpacing, kMaxOrigin).
#include <cmath>
#include <cstdio>
#include <string>

#include "core/volume_io.h"

namespace peakcast {

std::string spacing_refusal(const glm::dvec3& spacing, const glm::dvec3& origin) {
  char text[320];
  for (int a = 0; a < 3; ++a) {
    if (spacing[a] < kMinSpacing || spacing[a] > kMaxSpacing) {
      std::snprintf(text, sizeof text,
                    "spacing %g on axis %c is outside %g..%g: give it in a unit where it is nearer 1 (e.g. 4 nm, "
                    "not 4e-9 m; the unit travels with the volume)",
                    spacing[a], "xyz"[a], kMinSpacing, kMaxSpacing);
      return text;
    }
    if (!(std::fabs(origin[a]) <= kMaxOrigin)) {
      std::snprintf(text, sizeof text, "origin %g on axis %c is outside +-%g", origin[a], "xyz"[a], kMaxOrigin);
      return text;
    }
  }
  return "";
}

}  // namespace peakcast
