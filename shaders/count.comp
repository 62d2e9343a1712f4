// |O & P|, |P| and |R & P| for every hypothesis, from the bit-packed masks
// (R: the rim, bit 1 of the observation texture).
//
// An invocation walks one column of its layer's box over up to COUNT_ROWS
// rows. Instead of testing 32 bits per pixel it adds the pixel's word into
// nibble counters (4 words x 8 nibbles = the 32 bits, 15 pixels before a
// nibble can overflow), spills those into byte counters (COUNT_ROWS <= 255
// pixels), and finally adds pairs of 16-bit counters into shared memory: a
// handful of integer operations per pixel for all 32 hypotheses at once. One
// invocation per slot then adds the workgroup's sums to the global counts.

layout(local_size_x = COUNT_GROUP_WIDTH) in;

layout(binding = 0) uniform usampler2DArray u_masks;  // bit k of layer l: hypothesis 32 l + k
layout(binding = 1) uniform usampler2D u_observation;  // bit 0: observed (O), bit 1: rim (R)

layout(std430, binding = 4) readonly buffer BoxBuffer { ivec4 boxes[]; };  // per layer: x0, y0, x1, y1 (exclusive)
layout(std430, binding = 5) buffer CountBuffer { uint counts[]; };        // per hypothesis: |O & P|, |P|, |R & P|

uniform int u_hypotheses;

// [0, 16): |P|, [16, 32): |O & P|, [32, 48): |R & P|; each word holds two
// 16-bit counters.
const uint SLOTS = 48u;
shared uint s_sums[SLOTS];

const uint NIBBLE_ONES = 0x11111111u;
const uint LOW_NIBBLES = 0x0F0F0F0Fu;
const uint LOW_BYTES = 0x00FF00FFu;

void add_pairs(int slot, uvec4 even, uvec4 odd) {
  for (int j = 0; j < 4; ++j) {
    atomicAdd(s_sums[slot + j], even[j] & LOW_BYTES);
    atomicAdd(s_sums[slot + 4 + j], (even[j] >> 8) & LOW_BYTES);
    atomicAdd(s_sums[slot + 8 + j], odd[j] & LOW_BYTES);
    atomicAdd(s_sums[slot + 12 + j], (odd[j] >> 8) & LOW_BYTES);
  }
}

void main() {
  int layer = int(gl_WorkGroupID.z);
  ivec4 box = boxes[layer];
  int x = box.x + int(gl_GlobalInvocationID.x);
  int y0 = box.y + int(gl_WorkGroupID.y) * COUNT_ROWS;
  int y1 = min(y0 + COUNT_ROWS, box.w);
  uint t = gl_LocalInvocationIndex;
  for (uint i = t; i < SLOTS; i += uint(COUNT_GROUP_WIDTH)) s_sums[i] = 0u;
  barrier();

  if (x < box.z && y0 < y1) {
    // Byte counters: p_even[j] byte i counts bit 8i + j, p_odd[j] bit 8i + 4 + j.
    uvec4 p_even = uvec4(0u), p_odd = uvec4(0u), a_even = uvec4(0u), a_odd = uvec4(0u);
    uvec4 r_even = uvec4(0u), r_odd = uvec4(0u);
    const uvec4 shifts = uvec4(0u, 1u, 2u, 3u);
    for (int y = y0; y < y1;) {
      int run_end = min(y + 15, y1);
      // Nibble counters: p_nib[j] nibble n counts bit 4n + j.
      uvec4 p_nib = uvec4(0u), a_nib = uvec4(0u), r_nib = uvec4(0u);
      for (; y < run_end; ++y) {
        uint v = texelFetch(u_masks, ivec3(x, y, layer), 0).r;
        uint o = texelFetch(u_observation, ivec2(x, y), 0).r;
        uint a = (o & 1u) != 0u ? v : 0u;
        uint r = (o & 2u) != 0u ? v : 0u;
        p_nib += (uvec4(v) >> shifts) & NIBBLE_ONES;
        a_nib += (uvec4(a) >> shifts) & NIBBLE_ONES;
        r_nib += (uvec4(r) >> shifts) & NIBBLE_ONES;
      }
      p_even += p_nib & LOW_NIBBLES;
      p_odd += (p_nib >> 4u) & LOW_NIBBLES;
      a_even += a_nib & LOW_NIBBLES;
      a_odd += (a_nib >> 4u) & LOW_NIBBLES;
      r_even += r_nib & LOW_NIBBLES;
      r_odd += (r_nib >> 4u) & LOW_NIBBLES;
    }
    add_pairs(0, p_even, p_odd);
    add_pairs(16, a_even, a_odd);
    add_pairs(32, r_even, r_odd);
  }
  barrier();

  for (uint i = t; i < SLOTS; i += uint(COUNT_GROUP_WIDTH)) {
    uint sum = s_sums[i];
    // Slot s = 4 g + j holds bit 8 (g & 1) + 4 (g >> 1) + j in its low half
    // and that bit + 16 in its high half (see add_pairs).
    uint s = i & 15u;
    uint g = s >> 2, j = s & 3u;
    int bit = int(8u * (g & 1u) + 4u * (g >> 1) + j);
    // counts[3h] = |O & P|, counts[3h + 1] = |P|, counts[3h + 2] = |R & P|
    int which = i < 16u ? 1 : (i < 32u ? 0 : 2);
    int lo = layer * 32 + bit, hi = lo + 16;
    if ((sum & 0xFFFFu) != 0u && lo < u_hypotheses) atomicAdd(counts[3 * lo + which], sum & 0xFFFFu);
    if ((sum >> 16) != 0u && hi < u_hypotheses) atomicAdd(counts[3 * hi + which], sum >> 16);
  }
}
