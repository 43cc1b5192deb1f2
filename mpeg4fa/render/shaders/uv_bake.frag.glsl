#version 330 core
// Two float32 attachments: the texel's 3D position (alpha 1 marks a covered texel)
// and its interpolated normal (normalised on the CPU side).
in vec3 v_position;
in vec3 v_normal;

layout(location = 0) out vec4 out_position;
layout(location = 1) out vec4 out_normal;

void main() {
    out_position = vec4(v_position, 1.0);
    out_normal = vec4(v_normal, 0.0);
}
