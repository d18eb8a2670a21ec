// GL's per-macrocell tables (the lattice itself is ray/lattice.glsl).

// Byte c of a per-macrocell table (grid order, four bytes to a uint, low byte first).
#define cell_byte(table, c) \
  ((table[cell_index(c) >> 2] >> (8 * (cell_index(c) & 3))) & 0xFFu)
int cell_index(ivec3 c) { return c.x + P.cell_grid.x * (c.y + P.cell_grid.y * c.z); }

#ifdef ADAPTIVE
// Per macrocell: multiplier M, 1..8.
layout(std430, binding = SSBO_CELL_STRIDE) readonly buffer CellStride { uint u_cell_stride[]; };
#endif
