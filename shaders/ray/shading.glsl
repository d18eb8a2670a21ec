// Blinn-Phong with a head light (light at the eye): two-sided, white specular. The reference's
// is reference/shading.h.
SHARED_CONST float kAmbient = 0.3f;
SHARED_CONST float kDiffuse = 0.6f;
SHARED_CONST float kSpecular = 0.25f;
SHARED_CONST float kShininess = 32.0f;

// (The view direction is the ray's.)
vec3 shade(IN(Ray) r, vec3 rgb, vec3 gradient) {
  float len = length(gradient);
  if (len * r.min_spacing < 1e-5f) return rgb;
  vec3 n = gradient / len;
  float ndotl = abs(dot(n, -r.d));  // head light: the light's direction is the eye's, so h = l
  return rgb * (kAmbient + kDiffuse * ndotl) + vec3(kSpecular * pow(ndotl, kShininess));
}
