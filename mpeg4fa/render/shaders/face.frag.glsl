#version 330 core
// Materials: 0 skin (back faces: mouth interior), 1 left eye, 2 right eye, 3 teeth, 4 tongue.
// The eyes are drawn procedurally: sclera, then an iris disc of the FAPU's IRISD0 and a pupil
// whose diameter follows FAPs 29/30, both centred on the eyeball's gaze axis.
uniform vec3 camera_position;
uniform bool lighting;
uniform bool orthographic;
uniform vec3 view_direction;      // toward the camera, for orthographic views

uniform vec3 base_colour[6];      // skin, mouth, sclera, teeth, tongue, (unused)
uniform vec2 shine[6];            // specular strength, shininess
uniform vec3 lip_colour;
uniform vec3 iris_colour;
uniform vec3 pupil_colour;

uniform vec3 eye_centre[2];
uniform vec3 eye_axis[2];         // unit gaze direction
uniform float iris_radius;        // mm
uniform float pupil_radius[2];    // mm

uniform bool use_texture;
uniform sampler2D skin_texture;

uniform vec3 light_direction[2];  // toward the lights
uniform vec3 light_colour[2];
uniform vec3 ambient;

in vec3 v_position;
in vec3 v_normal;
in vec2 v_uv;
flat in int v_material;
in float v_lips;

out vec4 colour;

vec3 eye_colour(int eye, out int slot) {
    vec3 offset = v_position - eye_centre[eye];
    float along = dot(offset, eye_axis[eye]);
    float across = length(offset - along * eye_axis[eye]);
    slot = 2;
    if (along <= 0.0 || across > iris_radius * 1.08) return base_colour[2];
    if (across < pupil_radius[eye]) return pupil_colour;
    if (across > iris_radius) {                     // limbal ring, blended into the sclera
        float t = (across - iris_radius) / (0.08 * iris_radius);
        return mix(iris_colour * 0.45, base_colour[2], t);
    }
    float r = (across - pupil_radius[eye]) / max(iris_radius - pupil_radius[eye], 1e-3);
    float rays = 0.85 + 0.15 * sin(40.0 * atan(offset.y, offset.x));
    return iris_colour * mix(1.25, 0.7, r) * rays;
}

void main() {
    vec3 n = normalize(v_normal);
    int slot;
    vec3 base;
    if (v_material == 0) {
        if (gl_FrontFacing) {
            slot = 0;
            base = use_texture ? texture(skin_texture, v_uv).rgb : mix(base_colour[0], lip_colour, v_lips);
        } else {
            slot = 1;
            base = base_colour[1];
            n = -n;
        }
    } else if (v_material == 1 || v_material == 2) {
        base = eye_colour(v_material - 1, slot);
    } else {
        slot = v_material;   // 3 teeth, 4 tongue
        base = base_colour[slot];
    }
    if (!lighting) {
        colour = vec4(base, 1.0);
        return;
    }
    vec3 to_eye = orthographic ? view_direction : normalize(camera_position - v_position);
    vec3 light = ambient;
    float spec = 0.0;
    for (int i = 0; i < 2; ++i) {
        float lambert = max(dot(n, light_direction[i]), 0.0);
        light += lambert * light_colour[i];
        vec3 h = normalize(light_direction[i] + to_eye);
        spec += (lambert > 0.0 ? pow(max(dot(n, h), 0.0), shine[slot].y) : 0.0) * shine[slot].x;
    }
    if (slot == 1) light *= 0.55;   // the mouth interior is in shadow
    vec3 rgb = base * light + vec3(spec);
    colour = vec4(pow(clamp(rgb, 0.0, 1.0), vec3(1.0 / 1.15)), 1.0);
}
