// The ray and its sample lattice (docs/scenes.md). The ray is o + t d with o near the box (not
// at the eye), so t stays small even for a camera 1e6 away; t_eye is the eye's own parameter
// (rays start there). Lattice: sample j lies at t0 + j (B + A j / 2) (lattice.glsl).
struct Ray {
  vec3 o;
  vec3 d;
  float t_eye;
};

struct Lattice {
  float t0;
  float A;
  float B;
};
