# Headless (no RenderingDevice: gust on its own device, the texture filled from the snapshot). The wind
# answers the ambient before a first step; then it steps with the physics frames around a 2 m box until 20
# steps are taken, and the wind at points around the box is written to /gust/wind.txt ("x y z vx vy vz" a
# line) for gust_godot_reference to compare with gust's own answer for the same scene and steps.
extends SceneTree

const AMBIENT = Vector3(3, 0, 0)
var wind: GustWind3D
var failures := []
var done := false


func expect(ok: bool, what: String) -> void:
	if not ok:
		failures.append(what)


func _initialize() -> void:
	wind = GustWind3D.new()
	wind.cells = Vector3i(16, 8, 16)
	wind.cell_size = 0.5
	wind.ambient_wind = AMBIENT
	var early := wind.sample_wind(PackedVector3Array([Vector3(0.3, 0.2, 0.1), Vector3(100, 0, 0)]))
	expect(early.size() == 2 and early[0] == AMBIENT and early[1] == AMBIENT,
		"before a first step sample_wind gave %s, not the ambient %s" % [early, AMBIENT])
	root.add_child(wind)
	var box := MeshInstance3D.new()
	var mesh := BoxMesh.new()
	mesh.size = Vector3(2, 2, 2)
	box.mesh = mesh
	box.add_to_group("gust_obstacles")
	root.add_child(box)


func _process(_delta: float) -> bool:
	if done:
		return true
	var stats: Dictionary = wind.get_stats()
	if stats.steps < 20:
		return false
	wind.process_mode = Node.PROCESS_MODE_DISABLED
	done = true
	var points := PackedVector3Array()
	for x in range(-7, 8):
		for z in range(-3, 4):
			points.append(Vector3(x * 0.5 + 0.1, 0.3, z * 0.5 + 0.2))
	var velocities := wind.sample_wind(points)
	var file := FileAccess.open("/gust/wind.txt", FileAccess.WRITE)
	for i in range(points.size()):
		var p := points[i]
		var v := velocities[i]
		file.store_line("%.9f %.9f %.9f %.9f %.9f %.9f" % [p.x, p.y, p.z, v.x, v.y, v.z])
	file.close()
	FileAccess.open("/gust/steps.txt", FileAccess.WRITE).store_line(str(stats.steps))
	# The texture: 16x8x16 RGBA floats where the domain lies, centred on the node at the origin.
	var texture: Texture3D = wind.get_wind_texture()
	expect(texture != null and texture.get_width() == 16 and texture.get_height() == 8
		and texture.get_depth() == 16 and texture.get_format() == Image.FORMAT_RGBAF,
		"the wind texture is %s" % texture)
	var to_texture: Transform3D = wind.get_world_to_texture()
	expect((to_texture * Vector3(0, 0, 0)).is_equal_approx(Vector3(0.5, 0.5, 0.5))
		and (to_texture * Vector3(4, 2, 4)).is_equal_approx(Vector3(1, 1, 1)),
		"world_to_texture %s does not map the domain (-4 -2 -4)..(4 2 4) to 0..1" % to_texture)
	expect(stats.texture_bytes_through_cpu == 16 * 8 * 16 * 16,
		"%d bytes through the CPU a frame, not the texture's 32768" % stats.texture_bytes_through_cpu)
	if failures.is_empty():
		print("GUST_TEST PASS %d points after %d steps on %s" % [points.size(), stats.steps, stats.device])
	else:
		for f in failures:
			print("GUST_TEST FAIL: ", f)
	wind.free()
	quit(0 if failures.is_empty() else 1)
	return true
