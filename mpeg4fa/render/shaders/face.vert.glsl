#version 330 core
// Positions and normals in world space (mm); the camera matrix takes them to clip space.
uniform mat4 world_to_clip;
uniform bool uv_space;   // draw in texture space instead: the head's own colours baked into its UV image (Renderer.albedo)
uniform vec4 uv_frame;   // the part of the UV square drawn into the image there: origin, span (the teeth's own image)

in vec3 in_position;
in vec3 in_normal;
in vec2 in_uv;
in float in_material;
in vec2 in_tints;    // lips, oral cavity (0..1)
in vec2 in_detail;   // skin: brow coordinates; teeth: tooth coordinates (see render/details.py)
in vec2 in_nose;     // skin: nose wrinkle window and coordinate (mm)
in float in_neck;    // 1 on the neck (its back side is skin: render/scene.py)

out vec3 v_position;
out vec3 v_normal;
out vec2 v_uv;
flat out int v_material;
out vec2 v_tints;
out vec2 v_detail;
out vec2 v_nose;
out float v_neck;

void main() {
    v_position = in_position;
    v_normal = in_normal;
    v_uv = in_uv;
    v_material = int(in_material + 0.5);
    v_tints = in_tints;
    v_detail = in_detail;
    v_nose = in_nose;
    v_neck = in_neck;
    gl_Position = uv_space ? vec4(2.0 * (in_uv - uv_frame.xy) / uv_frame.zw - 1.0, 0.0, 1.0)
                           : world_to_clip * vec4(in_position, 1.0);
}
