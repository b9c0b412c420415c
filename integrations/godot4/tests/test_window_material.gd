# Forward+ under Xvfb on lavapipe: the wind reaches any material through the global shader parameters. A
# quad facing the camera shows the wind at each point as colour (0.5 + wind / 8, unshaded); in still air it
# is grey, and once the ambient wind is 4 m/s along X its red must rise to full (0.5 + 4/8) over the quad.
extends SceneTree

const SHADER = """
shader_type spatial;
render_mode unshaded;
global uniform sampler3D gust_wind_texture;
global uniform mat4 gust_world_to_texture;
varying vec3 world_position;
void vertex() {
	world_position = (MODEL_MATRIX * vec4(VERTEX, 1.0)).xyz;
}
void fragment() {
	vec3 wind = texture(gust_wind_texture, (gust_world_to_texture * vec4(world_position, 1.0)).xyz).rgb;
	ALBEDO = clamp(vec3(0.5) + wind / 8.0, 0.0, 1.0);
}
"""
var wind: GustWind3D
var frames := 0
var still: Image
var failures := []


func _initialize() -> void:
	wind = GustWind3D.new()
	wind.cells = Vector3i(16, 8, 16)
	wind.cell_size = 0.5
	root.add_child(wind)
	var camera := Camera3D.new()
	camera.position = Vector3(0, 0, 2)
	root.add_child(camera)


func add_quad() -> void:
	# After the first step: the extension has declared the global parameters the shader reads.
	var material := ShaderMaterial.new()
	material.shader = Shader.new()
	material.shader.code = SHADER
	var quad := MeshInstance3D.new()
	quad.mesh = QuadMesh.new()
	quad.mesh.size = Vector2(4, 4)
	quad.material_override = material
	root.add_child(quad)


func centre(image: Image) -> Color:
	return image.get_pixel(image.get_width() / 2, image.get_height() / 2)


func _process(_delta: float) -> bool:
	frames += 1
	if frames == 3:
		add_quad()
	elif frames == 8:
		still = root.get_texture().get_image()
		wind.ambient_wind = Vector3(4, 0, 0)
	elif frames == 14:
		var windy := root.get_texture().get_image()
		var a := centre(still)
		var b := centre(windy)
		var changed := 0
		for y in range(0, windy.get_height(), 4):
			for x in range(0, windy.get_width(), 4):
				if windy.get_pixel(x, y).r - still.get_pixel(x, y).r > 0.1:
					changed += 1
		var samples := (windy.get_width() / 4) * (windy.get_height() / 4)
		print("centre pixel in still air %s, in 4 m/s %s; %d of %d pixels redder" % [a, b, changed, samples])
		windy.save_png("/gust/windy.png")
		if not (abs(a.r - a.g) < 0.02 and abs(a.r - a.b) < 0.02 and a.r > 0.3):
			failures.append("in still air the quad is %s, not grey" % a)
		if not (b.r > 0.97 and b.r - a.r > 0.15):
			failures.append("with the wind the quad's red is %.3f (%.3f before), not full" % [b.r, a.r])
		if changed < samples / 2:
			failures.append("only %d of %d pixels turned redder" % [changed, samples])
		if failures.is_empty():
			print("GUST_TEST PASS")
		else:
			for f in failures:
				print("GUST_TEST FAIL: " + f)
		wind.free()
		quit(0 if failures.is_empty() else 1)
		return true
	return false
