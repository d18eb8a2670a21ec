// Blinn-Phong with a head light (light at the eye): two-sided, white specular. Mirrored by
// reference/shading.h.
const float kAmbient = 0.3, kDiffuse = 0.6, kSpecular = 0.25, kShininess = 32.0;

vec3 shade(vec3 rgb, vec3 gradient, vec3 view_dir) {
  float len = length(gradient);
  if (len * min(u_spacing.x, min(u_spacing.y, u_spacing.z)) < 1e-5) return rgb;
  vec3 n = gradient / len;
  vec3 l = -view_dir;  // head light: light direction = direction to the eye; so h = l
  float ndotl = abs(dot(n, l));
  return rgb * (kAmbient + kDiffuse * ndotl) + kSpecular * pow(ndotl, kShininess);
}
