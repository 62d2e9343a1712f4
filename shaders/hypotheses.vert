// One vertex of one hypothesis. Instance i is hypothesis i; 32 hypotheses
// share a layer of the R32UI target and hypothesis i owns bit i % 32 of it,
// so a whole generation is one instanced draw and a mask stays a union
// (logic-op OR) however its triangles overlap.

uniform mat4 u_clip;                         // world -> clip, target pixels, rows downwards
uniform vec4 u_planes[MAX_CLIP_PLANES];      // (n, d): keep n.x + d >= 0

out float gl_ClipDistance[MAX_CLIP_PLANES];
flat out uint v_bit;

void main() {
  int h = gl_InstanceID;
  vec4 p = vec4(world_point(mesh[gl_VertexID], h), 1.0);
  gl_Position = u_clip * p;
  for (int i = 0; i < MAX_CLIP_PLANES; ++i) gl_ClipDistance[i] = dot(u_planes[i], p);
  gl_Layer = h >> 5;
  v_bit = 1u << uint(h & 31);
}
