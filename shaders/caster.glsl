// The ray caster's program, shared by the fragment and compute entry points (raycast.frag,
// raycast.comp): the code both backends share (ray/, also compiled as C++ by the CPU backend)
// and GL's own parts (textures, buffers, the sampling loop), in the order GLSL needs them.
#include "ray/glsl_prelude.glsl"
#include "ray/uniforms.glsl"
#include "ray/types.glsl"
#include "ray/ray_setup.glsl"
#include "common_sampling.glsl"
#include "ray/lattice.glsl"
#include "ray/compositing.glsl"
#include "ray/shading.glsl"
#include "ray/catmull_rom.glsl"
#include "ray/brick.glsl"
#include "tf.glsl"
#include "raycast_body.glsl"
#include "output.glsl"
