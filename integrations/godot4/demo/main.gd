# gust's Godot 4 demo, built in code like the Godot 3 one (integrations/godot/demo): a ground, a box, a box that
# circles, a fan (a GustEmitter3D), a meadow of grass quads and a few trees whose shaders bend by the wind
# (the global shader parameters), and a character walking through them: a skinned mesh on a Skeleton3D whose
# legs and arms swing, in the obstacle group (the extension poses it from its bones, docs/godot.md). The
# box circles and the character walks while the wind is on. Command-line options after "--":
#   --frames N        quit after N frames (0: run until closed)
#   --wind on|off     start with the wind on (ambient breeze, fan, circling box) or off
#   --screenshot P    write the last frame to P (PNG)
#   --check           wind off, screenshot, wind on, screenshot; print GUST_DEMO PASS when the grass bent
#                     with the wind on and stood with it off (pixels compared) and, where Godot renders
#                     through a RenderingDevice, gust shared Godot's device with no texture byte through the
#                     CPU; the two frames written next to the --screenshot path
# It prints its frame rate and gust's step time when it quits.
extends Node3D

var wind: GustWind3D
var fan: GustEmitter3D
var mover: MeshInstance3D
var walker_skeleton: Skeleton3D
var frames := 0
var max_frames := 0
var wind_on := true
var screenshot := ""
var check := false
var step_ms := 0.0
var start_ms := 0


func _ready() -> void:
	var args := OS.get_cmdline_user_args()
	for i in range(args.size()):
		if args[i] == "--frames" and i + 1 < args.size():
			max_frames = int(args[i + 1])
		elif args[i] == "--wind" and i + 1 < args.size():
			wind_on = args[i + 1] != "off"
		elif args[i] == "--screenshot" and i + 1 < args.size():
			screenshot = args[i + 1]
		elif args[i] == "--check":
			check = true
	build_scene()
	set_wind(wind_on and not check)
	start_ms = Time.get_ticks_msec()


func box(size: Vector3, position_: Vector3, group: String) -> MeshInstance3D:
	var node := MeshInstance3D.new()
	var mesh := BoxMesh.new()
	mesh.size = size
	node.mesh = mesh
	node.position = position_
	node.add_to_group(group)
	add_child(node)
	return node


func build_scene() -> void:
	wind = GustWind3D.new()
	wind.cells = Vector3i(32, 8, 32)
	wind.cell_size = 0.5
	wind.position = Vector3(0, 1.9, 0)
	add_child(wind)
	fan = GustEmitter3D.new()
	fan.kind = 3 # cone
	fan.radius = 1.5
	fan.strength = 8.0
	fan.position = Vector3(-6, 0.8, 3)
	fan.rotation_degrees = Vector3(0, -90, 0) # -Z, the flow, along +X
	wind.add_child(fan)
	var ground := MeshInstance3D.new()
	var plane := PlaneMesh.new()
	plane.size = Vector2(16, 16)
	ground.mesh = plane
	ground.add_to_group("gust_obstacles")
	add_child(ground)
	box(Vector3(1.5, 1.5, 1.5), Vector3(-1, 0.75, -2), "gust_obstacles")
	mover = box(Vector3(1, 1, 1), Vector3(3, 0.5, 0), "gust_obstacles")
	build_walker()
	var camera := Camera3D.new()
	camera.position = Vector3(0, 7, 11)
	camera.rotation_degrees = Vector3(-32, 0, 0)
	add_child(camera)
	var sun := DirectionalLight3D.new()
	sun.rotation_degrees = Vector3(-50, 30, 0)
	add_child(sun)


# The grass and the trees: their shaders read the global parameters the extension declares at the wind's
# first step, so they are made after it.
func build_foliage() -> void:
	var grass := MultiMeshInstance3D.new()
	var blades := MultiMesh.new()
	blades.transform_format = MultiMesh.TRANSFORM_3D
	var quad := QuadMesh.new()
	quad.size = Vector2(0.08, 0.6)
	blades.mesh = quad
	blades.instance_count = 3600
	var rng := RandomNumberGenerator.new()
	rng.seed = 29
	for i in range(blades.instance_count):
		var t := Transform3D(Basis(Vector3.UP, rng.randf() * PI), Vector3(rng.randf_range(-7, 7), 0.3, rng.randf_range(-7, 7)))
		blades.set_instance_transform(i, t)
	grass.multimesh = blades
	var material := ShaderMaterial.new()
	material.shader = load("res://grass.gdshader")
	grass.material_override = material
	add_child(grass)
	var trunk_material := ShaderMaterial.new()
	trunk_material.shader = load("res://tree.gdshader")
	trunk_material.set_shader_parameter("colour", Color(0.4, 0.27, 0.15))
	var crown_material := ShaderMaterial.new()
	crown_material.shader = trunk_material.shader
	var tree_mesh := tree(trunk_material, crown_material)
	for p in [Vector3(-6, 0, -5), Vector3(-3.5, 0, -6.2), Vector3(4.5, 0, -5.5), Vector3(6.2, 0, -2.5), Vector3(-6.5, 0, 1), Vector3(6, 0, 3.5)]:
		var node := MeshInstance3D.new()
		node.mesh = tree_mesh
		node.position = p
		add_child(node)


# A tree as one mesh with its base at the origin: a trunk (cylinder) and a crown (sphere), each a surface with
# its material, both bent by tree.gdshader.
func tree(trunk_material: Material, crown_material: Material) -> ArrayMesh:
	var mesh := ArrayMesh.new()
	var trunk := CylinderMesh.new()
	trunk.top_radius = 0.1
	trunk.bottom_radius = 0.16
	trunk.height = 2.4
	var crown := SphereMesh.new()
	crown.radius = 1.0
	crown.height = 1.8
	for part in [[trunk, Vector3(0, 1.2, 0), trunk_material], [crown, Vector3(0, 3.0, 0), crown_material]]:
		var arrays: Array = part[0].get_mesh_arrays()
		var vertices: PackedVector3Array = arrays[Mesh.ARRAY_VERTEX]
		for i in range(vertices.size()):
			vertices[i] += part[1]
		arrays[Mesh.ARRAY_VERTEX] = vertices
		mesh.add_surface_from_arrays(Mesh.PRIMITIVE_TRIANGLES, arrays)
		mesh.surface_set_material(mesh.get_surface_count() - 1, part[2])
	return mesh


# The walker's bones: name, parent, rest position (relative to the parent), and its boxes: bone, size, centre
# (in the bind pose, the skeleton's space).
const BONES = [["hips", -1, Vector3(0, 0.95, 0)], ["torso", 0, Vector3(0, 0.05, 0)], ["leg_l", 0, Vector3(-0.15, 0, 0)], ["leg_r", 0, Vector3(0.15, 0, 0)], ["arm_l", 1, Vector3(-0.36, 0.6, 0)], ["arm_r", 1, Vector3(0.36, 0.6, 0)]]
const PARTS = [[1, Vector3(0.55, 0.65, 0.3), Vector3(0, 1.33, 0)], [1, Vector3(0.3, 0.3, 0.3), Vector3(0, 1.85, 0)], [2, Vector3(0.22, 0.95, 0.22), Vector3(-0.15, 0.475, 0)], [3, Vector3(0.22, 0.95, 0.22), Vector3(0.15, 0.475, 0)], [4, Vector3(0.16, 0.65, 0.16), Vector3(-0.36, 1.3, 0)], [5, Vector3(0.16, 0.65, 0.16), Vector3(0.36, 1.3, 0)]]


# A character built in code: a Skeleton3D of six bones, a skinned mesh of boxes (each box's vertices on one
# bone, weight 1) with a Skin binding bone i to the inverse of its rest, in the obstacle group.
func build_walker() -> void:
	walker_skeleton = Skeleton3D.new()
	var skin := Skin.new()
	var global_rests := []
	for i in range(BONES.size()):
		walker_skeleton.add_bone(BONES[i][0])
		walker_skeleton.set_bone_parent(i, BONES[i][1])
		walker_skeleton.set_bone_rest(i, Transform3D(Basis(), BONES[i][2]))
		walker_skeleton.reset_bone_pose(i)
		var origin: Vector3 = BONES[i][2] + (global_rests[BONES[i][1]] if BONES[i][1] >= 0 else Vector3())
		global_rests.append(origin)
		skin.add_bind(i, Transform3D(Basis(), -origin))
	var st := SurfaceTool.new()
	st.begin(Mesh.PRIMITIVE_TRIANGLES)
	for part in PARTS:
		var h: Vector3 = part[1] / 2
		var corners := []
		for c in range(8):
			corners.append(part[2] + Vector3(h.x if c & 1 else -h.x, h.y if c & 2 else -h.y, h.z if c & 4 else -h.z))
		for q in [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]:
			for c in [0, 2, 1, 0, 3, 2]:
				st.set_bones(PackedInt32Array([part[0], 0, 0, 0]))
				st.set_weights(PackedFloat32Array([1.0, 0.0, 0.0, 0.0]))
				st.add_vertex(corners[q[c]])
	st.generate_normals()
	var material := StandardMaterial3D.new()
	material.albedo_color = Color(0.85, 0.45, 0.2)
	st.set_material(material)
	var walker := MeshInstance3D.new()
	walker.mesh = st.commit()
	walker.skin = skin
	walker.add_to_group("gust_obstacles")
	walker_skeleton.add_child(walker)
	walker.skeleton = NodePath("..")
	add_child(walker_skeleton)
	walk(0.0)


# The walker at time t (s): along an ellipse through the meadow (about 1 m/s, from its front edge), legs
# and arms swinging.
func walk(t: float) -> void:
	var angle := 0.5 * PI - 0.25 * t
	var p := Vector3(4.5 * cos(angle), 0, 3.5 * sin(angle))
	var ahead := Vector3(-4.5 * sin(angle), 0, 3.5 * cos(angle)) * -1.0
	walker_skeleton.transform = Transform3D(Basis(Vector3.UP, atan2(ahead.x, ahead.z)), p)
	var swing := 0.5 * sin(5.0 * t)
	walker_skeleton.set_bone_pose_rotation(2, Quaternion(Vector3.RIGHT, swing))
	walker_skeleton.set_bone_pose_rotation(3, Quaternion(Vector3.RIGHT, -swing))
	walker_skeleton.set_bone_pose_rotation(4, Quaternion(Vector3.RIGHT, -0.8 * swing))
	walker_skeleton.set_bone_pose_rotation(5, Quaternion(Vector3.RIGHT, 0.8 * swing))


func set_wind(on: bool) -> void:
	wind_on = on
	wind.ambient_wind = Vector3(3, 0, 1) if on else Vector3.ZERO
	fan.strength = 8.0 if on else 0.0


func _physics_process(_delta: float) -> void:
	if wind_on:
		var t := frames / 60.0
		mover.position = Vector3(3 * cos(t), 0.5, 3 * sin(t))
		walk(t)


func _process(_delta: float) -> void:
	frames += 1
	if frames == 2:
		build_foliage()
	step_ms += wind.get_stats().step_ms
	if check:
		run_check()
	elif max_frames > 0 and frames >= max_frames:
		finish()


func grab() -> Image:
	return get_viewport().get_texture().get_image()


func differing(a: Image, b: Image) -> float:
	var count := 0
	for y in range(0, a.get_height(), 2):
		for x in range(0, a.get_width(), 2):
			var d := a.get_pixel(x, y) - b.get_pixel(x, y)
			if abs(d.r) + abs(d.g) + abs(d.b) > 0.1:
				count += 1
	return float(count) / float(a.get_width() * a.get_height() / 4)


var still_frame: Image
var calm_frame: Image


# Frame 20: the grass before any wind reached it. Frame 80: after 60 frames with the wind off (it must stand
# as before). Frame 200: after 120 frames with the wind on (it must bend).
func run_check() -> void:
	if frames == 20:
		still_frame = grab()
	elif frames == 80:
		calm_frame = grab()
		set_wind(true)
	elif frames == 200:
		var windy := grab()
		var calm := differing(still_frame, calm_frame)
		var bent := differing(still_frame, windy)
		if screenshot != "":
			calm_frame.save_png(screenshot.get_basename() + "_off.png")
			windy.save_png(screenshot)
		var stats: Dictionary = wind.get_stats()
		var shared: bool = RenderingServer.get_rendering_device() == null or (stats.shares_wind_image
			and stats.texture_bytes_through_cpu == 0)
		var ok := calm < 0.001 and bent > 0.01 and shared
		print("GUST_DEMO %s: pixels changed with the wind off %.4f, on %.4f; gust %s its wind image with Godot's device, %d texture bytes through the CPU a frame" % [
			"PASS" if ok else "FAIL", calm, bent, "shares" if stats.shares_wind_image else "does not share",
			stats.texture_bytes_through_cpu])
		finish()


func finish() -> void:
	var seconds := (Time.get_ticks_msec() - start_ms) / 1000.0
	if screenshot != "" and not check:
		grab().save_png(screenshot)
	var stats: Dictionary = wind.get_stats()
	print("GUST_DEMO %d frames in %.2f s: %.1f frames/s (%.1f ms a frame), gust's step %.1f ms a frame, %d texture bytes through the CPU a frame, %s, device %s" % [frames, seconds, frames / seconds, 1000.0 * seconds / frames, step_ms / frames, stats.texture_bytes_through_cpu, RenderingServer.get_current_rendering_method(), stats.device])
	get_tree().quit()
