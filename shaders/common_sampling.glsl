// Field reconstruction: hardware trilinear, or the cubic B-spline from 8 trilinear fetches
// (Sigg & Hadwiger 2005, cited as [29] in Knoll et al.). Positions in voxel coordinates
// (voxel i at i); values in TF coordinates.
layout(binding = UNIT_VOLUME) uniform sampler3D u_volume;

#ifdef TRICUBIC
float sample_raw(IN(Ray) r, vec3 x) {
  vec3 i = floor(x);
  vec3 f = x - i;
  vec3 f2 = f * f, f3 = f2 * f;
  vec3 w0 = (1.0 - 3.0 * f + 3.0 * f2 - f3) / 6.0;
  vec3 w1 = (4.0 - 6.0 * f2 + 3.0 * f3) / 6.0;
  vec3 w2 = (1.0 + 3.0 * f + 3.0 * f2 - 3.0 * f3) / 6.0;
  vec3 w3 = f3 / 6.0;
  vec3 g0 = w0 + w1, g1 = w2 + w3;
  vec3 h0 = (i - 1.0 + w1 / g0 + 0.5) * r.inv_dims;  // texture coordinates of the two fetches
  vec3 h1 = (i + 1.0 + w3 / g1 + 0.5) * r.inv_dims;
  float v000 = texture(u_volume, vec3(h0.x, h0.y, h0.z)).r, v100 = texture(u_volume, vec3(h1.x, h0.y, h0.z)).r;
  float v010 = texture(u_volume, vec3(h0.x, h1.y, h0.z)).r, v110 = texture(u_volume, vec3(h1.x, h1.y, h0.z)).r;
  float v001 = texture(u_volume, vec3(h0.x, h0.y, h1.z)).r, v101 = texture(u_volume, vec3(h1.x, h0.y, h1.z)).r;
  float v011 = texture(u_volume, vec3(h0.x, h1.y, h1.z)).r, v111 = texture(u_volume, vec3(h1.x, h1.y, h1.z)).r;
  float z0 = g0.y * (g0.x * v000 + g1.x * v100) + g1.y * (g0.x * v010 + g1.x * v110);
  float z1 = g0.y * (g0.x * v001 + g1.x * v101) + g1.y * (g0.x * v011 + g1.x * v111);
  return g0.z * z0 + g1.z * z1;
}
#else
float sample_raw(IN(Ray) r, vec3 x) { return texture(u_volume, (x + 0.5) * r.inv_dims).r; }
#endif

// The value in TF coordinates (the ray carries the frame's value map and texture size).
float sample_field(IN(Ray) r, vec3 x) { return sample_raw(r, x) * r.value_scale + r.value_bias; }

// Central differences one voxel apart, per world unit, in TF coordinates.
vec3 field_gradient(IN(Ray) r, vec3 x) {
  vec3 g;
  g.x = sample_field(r, x + vec3(1, 0, 0)) - sample_field(r, x - vec3(1, 0, 0));
  g.y = sample_field(r, x + vec3(0, 1, 0)) - sample_field(r, x - vec3(0, 1, 0));
  g.z = sample_field(r, x + vec3(0, 0, 1)) - sample_field(r, x - vec3(0, 0, 1));
  return g / (2.0 * r.spacing);
}
