#version 330 core
// Red: depth toward the camera (mm); green 1 marks pixels the head covers.
in float v_depth;

out vec4 out_depth;

void main() {
    out_depth = vec4(v_depth, 1.0, 0.0, 1.0);
}
