#version 330 core
// The skin drawn in texture space: each corner lands at its UV, so every covered
// texel receives the surface point (and normal) that the texture shows there.
in vec3 in_position;
in vec3 in_normal;
in vec2 in_uv;

out vec3 v_position;
out vec3 v_normal;

void main() {
    v_position = in_position;
    v_normal = in_normal;
    gl_Position = vec4(in_uv * 2.0 - 1.0, 0.0, 1.0);
}
