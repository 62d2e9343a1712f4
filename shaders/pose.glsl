// Posing the gripper model from a hypothesis vector: the math of
// framework/include/gtrack/model.hpp (ArticulatedModel::pose), in float.
//
// The mesh is pulled from a buffer by gl_VertexID rather than fed as vertex
// attributes, so that one upload serves every hypothesis and the vertex shader
// alone decides where a vertex goes.

struct MeshVertex {
  vec2 ab;     // along the link from its hinge (or palm x), across it (or palm y)
  int finger;  // -1 for the palm
  int link;
};

layout(std430, binding = 0) readonly buffer MeshBuffer { MeshVertex mesh[]; };
// Per finger: base point (xy) and outward unit direction (zw).
layout(std430, binding = 1) readonly buffer FingerBuffer { vec4 fingers[]; };
// Link lengths, u_max_links entries per finger.
layout(std430, binding = 2) readonly buffer LinkBuffer { float link_lengths[]; };
// Hypotheses one after another, u_dims floats each: x y z rx ry rz q1..qF.
layout(std430, binding = 3) readonly buffer HypothesisBuffer { float hypotheses[]; };

uniform int u_dims;
uniform int u_max_links;

// R = Rz(rz) * Ry(ry) * Rx(rx), angles in degrees.
mat3 rotation_from_euler_deg(vec3 r) {
  vec3 c = cos(radians(r));
  vec3 s = sin(radians(r));
  return mat3(vec3(c.z * c.y, s.z * c.y, -s.y),
              vec3(c.z * s.y * s.x - s.z * c.x, s.z * s.y * s.x + c.z * c.x, c.y * s.x),
              vec3(c.z * s.y * c.x + s.z * s.x, s.z * s.y * c.x - c.z * s.x, c.y * c.x));
}

vec3 model_point(MeshVertex v, int base) {
  if (v.finger < 0) return vec3(v.ab, 0.0);
  float q = radians(hypotheses[base + 6 + v.finger]);
  // Hinge of link j in the finger's (radial, z) plane: the sum of the links
  // before it, link i tilted by (i + 1) q.
  vec2 hinge = vec2(0.0);
  for (int j = 0; j < v.link; ++j) {
    float t = float(j + 1) * q;
    hinge += link_lengths[v.finger * u_max_links + j] * vec2(cos(t), sin(t));
  }
  float t = float(v.link + 1) * q;
  vec2 rz = hinge + v.ab.x * vec2(cos(t), sin(t));
  vec4 f = fingers[v.finger];
  vec2 lateral = vec2(-f.w, f.z);
  return vec3(f.xy + rz.x * f.zw + v.ab.y * lateral, rz.y);
}

vec3 world_point(MeshVertex v, int hypothesis) {
  int base = hypothesis * u_dims;
  vec3 t = vec3(hypotheses[base], hypotheses[base + 1], hypotheses[base + 2]);
  vec3 r = vec3(hypotheses[base + 3], hypotheses[base + 4], hypotheses[base + 5]);
  return rotation_from_euler_deg(r) * model_point(v, base) + t;
}
