#version 330 core
// The head seen along one photo's axis (an orthographic map into photo pixels);
// the depth written out is the distance toward the camera in mm (larger = nearer).
uniform mat4 world_to_clip;
uniform vec3 toward_camera;

in vec3 in_position;

out float v_depth;

void main() {
    v_depth = dot(in_position, toward_camera);
    gl_Position = world_to_clip * vec4(in_position, 1.0);
}
