#version 330 core
// Materials: 0 skin (back faces: the inside of the head), 1 left eye, 2 right eye, 3 teeth, 4 tongue;
// slot 5 is the gums (teeth above their gum line).
// The eyes are drawn procedurally: sclera, then an iris disc of the FAPU's IRISD0 and a pupil
// whose diameter follows FAPs 29/30, both centred on the eyeball's gaze axis.
// The skin mixes in the lip and brow colours (untextured only) and the dark of the oral cavity;
// the teeth get their shape from tooth coordinates: gaps, rounded tips, scalloped gums.
// Unlit, every part is one flat colour (the tests classify pixels by it): brows, cavity and gums
// are then pure where their weight is 1, and hair strokes and tooth gaps are left out.
uniform vec3 camera_position;
uniform bool lighting;
uniform bool orthographic;
uniform vec3 view_direction;      // toward the camera, for orthographic views

uniform vec3 base_colour[6];      // skin, mouth, sclera, teeth, tongue, gums
uniform vec2 shine[6];            // specular strength, shininess
uniform vec3 lip_colour;
uniform vec3 brow_colour;
uniform vec3 cavity_colour;
uniform vec3 iris_colour;
uniform vec3 pupil_colour;

uniform vec3 eye_centre[2];
uniform vec3 eye_axis[2];         // unit gaze direction
uniform float iris_radius;        // mm
uniform float pupil_radius[2];    // mm

uniform float nose_wrinkle;       // 0..1 (face/looks.py)

uniform bool use_texture;
uniform sampler2D skin_texture;

uniform vec3 light_direction[2];  // toward the lights
uniform vec3 light_colour[2];
uniform vec3 ambient;

in vec3 v_position;
in vec3 v_normal;
in vec2 v_uv;
flat in int v_material;
in vec2 v_tints;
in vec2 v_detail;
in vec2 v_nose;

out vec4 colour;

const float TOOTH_MM = 7.0;       // a typical tooth width, for the tip rounding
const float TIP_MM = 1.1;         // radius of a tooth's rounded corners
const float CROWN_MM = 9.5;       // crown height at the middle of a tooth (gum line above)
const float WRINKLE_MM = 4.2;     // spacing of the nose creases
const float BACK_TEETH_SHADE = 0.3;  // premolars and molars: the light that reaches inside the mouth

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

// How much brow covers this point: (along 0 inner .. 1 outer, height above the brow curve, mm).
float brow_cover(vec2 d) {
    float along = d.x;
    if (along < -0.06 || along > 1.08) return 0.0;
    float inner = clamp((along + 0.05) / 0.09, 0.0, 1.0);   // a rounded inner end
    float outer = clamp((1.07 - along) / 0.3, 0.0, 1.0);    // a tapered outer end
    float half_width = (3.3 - 1.9 * clamp(along, 0.0, 1.0)) * inner * (2.0 - inner) * outer * (2.0 - outer);
    float cover = clamp((half_width - abs(d.y + 0.4)) / 0.9 + 0.5, 0.0, 1.0);
    if (lighting) cover *= 0.8 + 0.4 * abs(fract(27.0 * along + 0.35 * d.y) - 0.5);   // hair strokes
    return cover;
}

void main() {
    vec3 n = normalize(v_normal);
    vec3 to_eye = orthographic ? view_direction : normalize(camera_position - v_position);
    int slot;
    vec3 base;
    float shade = 1.0;
    if (v_material == 0) {
        if (gl_FrontFacing) {
            slot = 0;
            if (use_texture) {
                base = texture(skin_texture, v_uv).rgb;
            } else {
                base = mix(base_colour[0], lip_colour, v_tints.x);
                base = mix(base, brow_colour, 0.9 * brow_cover(v_detail));
            }
            base = mix(base, cavity_colour, v_tints.y);
            shade = 1.0 - 0.85 * v_tints.y;
            float w = nose_wrinkle * v_nose.x;
            if (w > 0.0) {                                // creases across the upper nose: the skin bunches
                float phase = 6.2831853 * v_nose.y / WRINKLE_MM;
                n = normalize(n + 0.4 * w * sin(phase) * vec3(0.0, 1.0, 0.0));
                shade *= 1.0 - 0.22 * w * pow(0.5 + 0.5 * cos(phase), 4.0);
            }
        } else {
            slot = 1;
            base = base_colour[1];
            n = -n;
            shade = 0.55;
        }
    } else if (v_material == 1 || v_material == 2) {
        base = eye_colour(v_material - 1, slot);
    } else if (v_material == 3) {
        float f = fract(v_detail.x);                      // across one tooth, 0 and 1 at the gaps
        float from_gap = (0.5 - abs(f - 0.5)) * TOOTH_MM;  // mm from the nearest gap
        float h = v_detail.y;                             // mm from the biting edge
        vec2 corner = vec2(TIP_MM) - vec2(from_gap, h);
        bool notch = corner.x > 0.0 && corner.y > 0.0 && length(corner) > TIP_MM;
        if (notch) {                                      // outside a rounded tip: the dark behind
            slot = 1;
            base = cavity_colour;
            shade = 0.15;
        } else if (h > CROWN_MM * (0.8 + 0.8 * f * (1.0 - f))) {
            slot = 5;                                     // gum, scalloped between the teeth
            base = base_colour[5];
        } else {
            slot = 3;
            base = base_colour[3];
            // each tooth bulges: tilt the normal across the tooth; the thin band's normals turn
            // down at the biting edge, so lean them toward the viewer (a tooth's labial face)
            // (front teeth only: seen from the side, the molars' bulges and gaps read as stripes)
            float back = smoothstep(2.0, 4.0, abs(v_detail.x));
            if (dot(n, to_eye) < 0.0) n = -n;
            n = normalize(n + 0.7 * to_eye + cross(vec3(0.0, 1.0, 0.0), n) * (1.8 * f - 0.9) * (1.0 - back));
            if (lighting) shade = mix(mix(0.55, 1.0, smoothstep(0.0, 0.35, from_gap)), 0.9, back);  // the gaps
            // teeth further back along the arch sit deeper in the mouth, in its shadow
            shade *= mix(1.0, BACK_TEETH_SHADE, smoothstep(2.0, 5.0, abs(v_detail.x)));
        }
    } else {
        slot = v_material;   // 4 tongue
        base = base_colour[slot];
    }
    if (!lighting) {
        colour = vec4(base, 1.0);
        return;
    }
    vec3 light = ambient;
    float spec = 0.0;
    for (int i = 0; i < 2; ++i) {
        float lambert = max(dot(n, light_direction[i]), 0.0);
        light += lambert * light_colour[i];
        vec3 h = normalize(light_direction[i] + to_eye);
        spec += (lambert > 0.0 ? pow(max(dot(n, h), 0.0), shine[slot].y) : 0.0) * shine[slot].x;
    }
    vec3 rgb = (base * light + vec3(spec)) * shade;
    colour = vec4(pow(clamp(rgb, 0.0, 1.0), vec3(1.0 / 1.15)), 1.0);
}
