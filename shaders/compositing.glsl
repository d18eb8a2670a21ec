// Front-to-back emission-absorption (docs/scenes.md): colour not premultiplied in the TF.
void composite(inout vec4 acc, vec3 rgb, float alpha) {
  float w = (1.0 - acc.a) * alpha;
  acc.rgb += w * rgb;
  acc.a += w;
}

vec3 finish_pixel(vec4 acc) { return acc.rgb + (1.0 - acc.a) * u_background.rgb; }
