#version 330 core
// Positions and normals in world space (mm); the camera matrix takes them to clip space.
uniform mat4 world_to_clip;

in vec3 in_position;
in vec3 in_normal;
in vec2 in_uv;
in float in_material;
in float in_lips;

out vec3 v_position;
out vec3 v_normal;
out vec2 v_uv;
flat out int v_material;
out float v_lips;

void main() {
    v_position = in_position;
    v_normal = in_normal;
    v_uv = in_uv;
    v_material = int(in_material + 0.5);
    v_lips = in_lips;
    gl_Position = world_to_clip * vec4(in_position, 1.0);
}
