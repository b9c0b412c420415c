// Trees bent by gust's wind texture, like the grass (grass.shader): the whole tree sways with the wind at its
// crown, more the higher a vertex is above the tree's base (the MeshInstance's origin): nothing at the root,
// the most at the top, so the trunk bends instead of sliding.
shader_type spatial;
render_mode world_vertex_coords;

uniform sampler3D gust_wind;
uniform mat4 gust_world_to_texture;
uniform float height = 3.0;      // m from the base to the crown's centre, where the wind is read
uniform float stiffness = 0.05;  // metres of sway per m/s of wind at `height`
uniform vec4 colour : hint_color = vec4(0.2, 0.45, 0.12, 1.0);

void vertex() {
	vec3 base = WORLD_MATRIX[3].xyz;
	vec3 uvw = (gust_world_to_texture * vec4(base + vec3(0.0, height, 0.0), 1.0)).xyz;
	vec3 wind = texture(gust_wind, uvw).xyz;
	float h = max(VERTEX.y - base.y, 0.0) / height;
	vec2 sway = wind.xz * stiffness * h * h;
	VERTEX.xz += sway;
	VERTEX.y -= 0.5 * dot(sway, sway) * h / height;
}

void fragment() {
	ALBEDO = colour.rgb;
}
