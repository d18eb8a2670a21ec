// Distributed rendering (docs/distributed.md): which lattice points of a ray a brick owns. Every
// rank computes a point's whole-volume voxel coordinates alike, so exactly one rank owns it.

// Lattice point i lies in this brick's own box. P.open_lo / P.open_hi: the axes whose bound is
// the volume's own face (none there: rounding may put a point a hair outside).
bool owns(IN(Ray) r, IN(Lattice) L, int i) {
  // PRECISE: no contraction, so every call site (and every rank) computes the same x; the two
  // ranks at a face decide a shared point at different call sites of clip_to_brick.
  float j = float(i);
  PRECISE float t = L.t0 + j * (L.B + L.A * j * 0.5f);  // lattice_t
  PRECISE vec3 x = (r.o + t * r.d + P.box_half) * P.inv_spacing;
  for (int a = 0; a < 3; ++a) {
    bool lo_ok = ((P.open_lo >> a) & 1) != 0 || x[a] >= P.own_lo[a];
    bool hi_ok = ((P.open_hi >> a) & 1) != 0 || x[a] < P.own_hi[a];
    if (!(lo_ok && hi_ok)) return false;
  }
  return true;
}

// The lattice index nearest t (in the span), halves rounded up, at most `last`.
int index_near(IN(Lattice) L, float t, vec2 span, int last) {
  float x = lattice_index(L, clamp(t, span.x, span.y));
  float i = floor(x);
  if (x - i >= 0.5f) i += 1.0f;
  return (i <= 0.0f || isnan(i)) ? 0 : (i >= float(last) ? last : int(i));
}

// Restricts the ray to the points it owns: a first guess from the ray's interval in the own box
// (axes the ray does not move along, and faces on the volume's own faces, do not bound it), then
// owns() decides at both ends, moving them until they agree with it (the owned points are
// consecutive: the box is convex and the points' coordinates are monotone along the ray; the
// guess may be off by more than a point where the ray is nearly parallel to a face). False when
// it owns none; else own_first..own_last, and `last` becomes the last point the walk visits.
bool clip_to_brick(IN(Ray) r, IN(Lattice) L, vec2 span, INOUT(int) last, OUT(int) own_first, OUT(int) own_last) {
  own_first = 0;  // an OUT parameter is undefined in GLSL until written: written on every path
  own_last = -1;
  if (last < 0) return false;
  vec3 lo = P.own_lo * P.spacing - P.box_half, hi = P.own_hi * P.spacing - P.box_half;
  float t_in = -kHuge, t_out = kHuge;
  for (int a = 0; a < 3; ++a) {
    if (abs(r.d[a]) < 1e-20f) continue;
    float t_lo = ((P.open_lo >> a) & 1) != 0 ? (r.d[a] > 0.0f ? -kHuge : kHuge) : (lo[a] - r.o[a]) / r.d[a];
    float t_hi = ((P.open_hi >> a) & 1) != 0 ? (r.d[a] > 0.0f ? kHuge : -kHuge) : (hi[a] - r.o[a]) / r.d[a];
    t_in = max(t_in, min(t_lo, t_hi));
    t_out = min(t_out, max(t_lo, t_hi));
  }
  if (!(t_in <= t_out)) {
    t_in = 0.5f * (max(t_in, span.x) + min(t_out, span.y));
    t_out = t_in;
  }
  int first = index_near(L, t_in, span, last);
  int final_ = max(first, index_near(L, t_out, span, last));
  while (first <= final_ && !owns(r, L, first)) ++first;
  while (final_ >= first && !owns(r, L, final_)) --final_;
  if (first > final_) return false;
  while (first > 0 && owns(r, L, first - 1)) --first;
  while (final_ < last && owns(r, L, final_ + 1)) ++final_;
  own_first = first;
  own_last = final_;
  // Virtual samples: the two visits after the last owned point (the Catmull-Rom window of its
  // segment), and one more, so that whether the second is visited is decided as in one process
  // (a run of occupied cells starting there visits the point before it). Adaptive sampling: each
  // visit is up to kMaxAdaptiveMultiplier (8) points on, and the last owned visit's step (its
  // multiplier, cut at its cell's last point) is decided as in one process only when the walk goes
  // on past it. (The segment out of the last owned point is drawn by the rank owning its end.)
  int m = V.adaptive ? 8 : 1;
  int beyond = V.virtual_samples != 0 ? 2 * m + 1 : (V.adaptive ? m : 0);
  last = min(final_ + beyond, last);
  return true;
}
