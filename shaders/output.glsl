// The value an entry point stores for a pixel. RGB8_OUTPUT: the colour over the background,
// quantised to 8 bits exactly as encode::to_rgb8 does on the CPU (non-finite -> 0, clamp to
// [0, 1], times 255 in float, round half away from zero), so a streamed frame equals the
// CLI's PNG of the same scene byte for byte. Otherwise RGBA float (a = opacity).
#ifdef RGB8_OUTPUT
uvec4 output_color(vec4 acc) {
  vec3 c = finish_pixel(acc);
  uvec4 q = uvec4(0u, 0u, 0u, 255u);
  for (int k = 0; k < 3; ++k) {
    float v = (isnan(c[k]) || isinf(c[k])) ? 0.0 : clamp(c[k], 0.0, 1.0);
    precise float y = v * 255.0;  // precise: no fused multiply-add, the same rounding as the CPU
    uint n = uint(y);             // floor, y >= 0
    if (y - float(n) >= 0.5) n += 1u;  // exact subtraction: lround's halves go up
    q[k] = n;
  }
  return q;
}
#elif defined(BRICK)
vec4 output_color(vec4 acc) { return acc; }  // one brick's layer: premultiplied, no background
#else
vec4 output_color(vec4 acc) { return vec4(finish_pixel(acc), acc.a); }
#endif
