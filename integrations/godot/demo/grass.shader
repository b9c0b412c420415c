// Grass blades bent by gust's wind texture. GustWind sets gust_wind (velocity in m/s per cell, rgb) and
// gust_world_to_texture (world position -> texture coordinates) on every ShaderMaterial of its material group.
shader_type spatial;
render_mode world_vertex_coords, cull_disabled;

uniform sampler3D gust_wind;
uniform mat4 gust_world_to_texture;
uniform float stiffness = 0.06; // metres of sway per m/s of wind at the tip of a 1 m blade
uniform vec4 colour : hint_color = vec4(0.25, 0.55, 0.15, 1.0);

void vertex() {
	float height = UV.y < 0.5 ? 1.0 : 0.0; // QuadMesh: v = 0 at the top edge
	vec3 uvw = (gust_world_to_texture * vec4(VERTEX, 1.0)).xyz;
	vec3 wind = texture(gust_wind, uvw).xyz;
	vec2 sway = wind.xz * stiffness * height;
	VERTEX.xz += sway;
	VERTEX.y -= 0.5 * dot(sway, sway) * height;
}

void fragment() {
	ALBEDO = colour.rgb * (0.6 + 0.4 * (1.0 - UV.y));
}
