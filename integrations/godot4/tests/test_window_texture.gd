# Forward+ under Xvfb on lavapipe. gust must share its wind image with Godot's Vulkan device: the texture is a
# Texture3DRD over the RGBA16F copy gust exported and Godot imported, no byte of it goes through the CPU, and after 20 steps
# around a box with a fan, read back through Godot's RenderingDevice, it equals the snapshot that sample_wind
# answers from at every cell centre within half-float rounding (docs/godot.md, "Where the wind image lives").
extends SceneTree

const CELLS = Vector3i(16, 8, 16)
var wind: GustWind3D
var failures := []


func expect(ok: bool, what: String) -> void:
	if not ok:
		failures.append(what)


func _initialize() -> void:
	expect(RenderingServer.get_current_rendering_method() == "forward_plus"
		and RenderingServer.get_current_rendering_driver_name() == "vulkan",
		"rendering with %s on %s, not forward_plus on vulkan" % [RenderingServer.get_current_rendering_method(),
		RenderingServer.get_current_rendering_driver_name()])
	wind = GustWind3D.new()
	wind.cells = CELLS
	wind.cell_size = 0.5
	wind.ambient_wind = Vector3(3, 0, 1)
	root.add_child(wind)
	var fan := GustEmitter3D.new()
	fan.position = Vector3(-2, 0, 0)
	fan.strength = 6.0
	wind.add_child(fan)
	var box := MeshInstance3D.new()
	box.mesh = BoxMesh.new()
	box.add_to_group("gust_obstacles")
	root.add_child(box)


var frames := 0


func _process(_delta: float) -> bool:
	frames += 1
	var stats: Dictionary = wind.get_stats()
	if stats.steps < 20 and frames < 300:
		return false
	expect(stats.steps >= 20, "%d steps in %d frames" % [stats.steps, frames])
	wind.process_mode = Node.PROCESS_MODE_DISABLED
	var texture: Texture3D = wind.get_wind_texture()
	var rd := RenderingServer.get_rendering_device()
	var shared: bool = stats.shares_wind_image
	print("gust %s its wind image with Godot's device, %d texture bytes through the CPU a frame" % ["shares" if shared else "does not share", stats.texture_bytes_through_cpu])
	expect(shared, "gust does not share its wind image with Godot's device")
	expect(stats.texture_bytes_through_cpu == 0, "%d bytes through the CPU a frame" % stats.texture_bytes_through_cpu)
	expect(texture is Texture3DRD, "the wind texture is %s, not a Texture3DRD" % texture)
	if texture is Texture3DRD:
		compare(read_back(rd, (texture as Texture3DRD).texture_rd_rid))
	if failures.is_empty():
		print("GUST_TEST PASS after %d steps on %s" % [stats.steps, stats.device])
	else:
		for f in failures:
			print("GUST_TEST FAIL: ", f)
	wind.free()
	quit(0 if failures.is_empty() else 1)
	return true


# The texture's texels through Godot's RenderingDevice. Godot 4.6.3's texture_get_data cannot read a texture
# made from an extension's image (its driver knows no extent for it and copies rows of width 0), so the wind is
# copied on the GPU into a texture of Godot's own (texture_copy), which texture_get_data reads.
func read_back(rd: RenderingDevice, shared: RID) -> PackedByteArray:
	var format := RDTextureFormat.new()
	format.texture_type = RenderingDevice.TEXTURE_TYPE_3D
	format.format = RenderingDevice.DATA_FORMAT_R16G16B16A16_SFLOAT
	format.width = CELLS.x
	format.height = CELLS.y
	format.depth = CELLS.z
	format.usage_bits = (RenderingDevice.TEXTURE_USAGE_SAMPLING_BIT | RenderingDevice.TEXTURE_USAGE_CAN_COPY_TO_BIT
		| RenderingDevice.TEXTURE_USAGE_CAN_COPY_FROM_BIT)
	var copy := rd.texture_create(format, RDTextureView.new())
	expect(rd.texture_copy(shared, copy, Vector3.ZERO, Vector3.ZERO, Vector3(CELLS), 0, 0, 0, 0) == OK,
		"texture_copy from the wind texture failed")
	var bytes := rd.texture_get_data(copy, 0)
	rd.free_rid(copy)
	return bytes


func compare(bytes: PackedByteArray) -> void:
	var n := CELLS.x * CELLS.y * CELLS.z
	expect(bytes.size() == n * 8, "read back %d bytes, not %d RGBA16F texels" % [bytes.size(), n])
	if bytes.size() != n * 8:
		return
	var from_texture := wind.get_world_to_texture().affine_inverse()
	var points := PackedVector3Array()
	for k in range(CELLS.z):
		for j in range(CELLS.y):
			for i in range(CELLS.x):
				points.append(from_texture * Vector3((i + 0.5) / CELLS.x, (j + 0.5) / CELLS.y, (k + 0.5) / CELLS.z))
	var snapshot := wind.sample_wind(points)
	var worst := 0.0
	var bad := 0
	var fastest := 0.0
	for c in range(n):
		var texel := Vector3(bytes.decode_half(8 * c), bytes.decode_half(8 * c + 2), bytes.decode_half(8 * c + 4))
		# A half has 11 significant bits: rounding moves a value by at most 2^-11 of it (and below 2^-14,
		# subnormals, by 2^-25).
		var tolerance := snapshot[c].abs() * pow(2.0, -11) + Vector3.ONE * pow(2.0, -24)
		var d := (texel - snapshot[c]).abs()
		if d.x > tolerance.x or d.y > tolerance.y or d.z > tolerance.z:
			bad += 1
			if bad <= 3:
				print("cell %d at %s: texture %s, snapshot %s" % [c, points[c], texel, snapshot[c]])
		worst = max(worst, max(d.x, max(d.y, d.z)))
		fastest = max(fastest, snapshot[c].length())
	print("%d cells, %d beyond the tolerance, largest difference %.6f m/s, fastest %.3f m/s" % [n, bad, worst, fastest])
	expect(bad == 0, "%d cells of the texture differ from the snapshot" % bad)
	expect(fastest > 4.0, "the fastest wind is %.3f m/s: the fan and the box left no mark" % fastest)
