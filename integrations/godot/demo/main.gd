# gust's Godot demo, built in code: a ground, a box, a box that circles, a fan (a GustEmitter) and a meadow of
# grass quads whose shader bends by GustWind's texture. Command-line options after "--":
#   --frames N        quit after N frames (0: run until closed)
#   --wind on|off     start with the wind on (ambient breeze, fan, circling box) or off
#   --screenshot P    write the last frame to P (PNG; needs a window: godot3-runner)
#   --check           wind off, screenshot, wind on, screenshot; print GUST_DEMO PASS when the grass bent
#                     with the wind on and stood with it off (pixels compared), with the two frames written
#                     next to the --screenshot path
# It prints its frame rate and gust's share of the frame time when it quits.
extends Spatial

const GustWind = preload("res://addons/gust/gust_wind.gdns")
const GustEmitter = preload("res://addons/gust/gust_emitter.gdns")

var wind
var fan
var mover
var frames = 0
var max_frames = 0
var wind_on = true
var screenshot = ""
var check = false
var step_ms = 0.0
var publish_ms = 0.0
var start_ms = 0

func _ready():
	var args = OS.get_cmdline_args()
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
	start_ms = OS.get_ticks_msec()

func box(size, position, group):
	var node = MeshInstance.new()
	var cube = CubeMesh.new()
	cube.size = size
	node.mesh = cube
	node.translation = position
	node.add_to_group(group)
	add_child(node)
	return node

func build_scene():
	wind = GustWind.new()
	wind.cells = Vector3(32, 8, 32)
	wind.cell_size = 0.5
	wind.voxels_per_cell = 2
	wind.translation = Vector3(0, 1.9, 0)
	add_child(wind)
	fan = GustEmitter.new()
	fan.type = 4 # cone motor
	fan.radius = 1.5
	fan.length = 5.0
	fan.strength = 8.0
	fan.translation = Vector3(-6, 0.8, 3)
	fan.rotation_degrees = Vector3(0, -90, 0) # -Z, the flow, along +X
	wind.add_child(fan)
	var ground = MeshInstance.new()
	var plane = PlaneMesh.new()
	plane.size = Vector2(16, 16)
	ground.mesh = plane
	ground.add_to_group("gust_obstacles")
	add_child(ground)
	box(Vector3(1.5, 1.5, 1.5), Vector3(-1, 0.75, -2), "gust_obstacles")
	mover = box(Vector3(1, 1, 1), Vector3(3, 0.5, 0), "gust_obstacles")
	var grass = MultiMeshInstance.new()
	var blades = MultiMesh.new()
	blades.transform_format = MultiMesh.TRANSFORM_3D
	var quad = QuadMesh.new()
	quad.size = Vector2(0.08, 0.6)
	blades.mesh = quad
	blades.instance_count = 3600
	var rng = RandomNumberGenerator.new()
	rng.seed = 29
	for i in range(blades.instance_count):
		var t = Transform(Basis(Vector3.UP, rng.randf() * PI), Vector3(rng.randf_range(-7, 7), 0.3, rng.randf_range(-7, 7)))
		blades.set_instance_transform(i, t)
	grass.multimesh = blades
	var material = ShaderMaterial.new()
	material.shader = load("res://grass.shader")
	grass.material_override = material
	grass.add_to_group("gust_wind_materials")
	add_child(grass)
	var camera = Camera.new()
	camera.translation = Vector3(0, 7, 11)
	camera.rotation_degrees = Vector3(-32, 0, 0)
	add_child(camera)
	var sun = DirectionalLight.new()
	sun.rotation_degrees = Vector3(-50, 30, 0)
	add_child(sun)

func set_wind(on):
	wind_on = on
	wind.ambient = Vector3(3, 0, 1) if on else Vector3.ZERO
	fan.enabled = on

func _physics_process(delta):
	if wind_on:
		var t = frames / 60.0
		mover.translation = Vector3(3 * cos(t), 0.5, 3 * sin(t))

func _process(_delta):
	frames += 1
	step_ms += wind.get_step_ms()
	publish_ms += wind.get_publish_ms()
	if check:
		run_check()
	elif max_frames > 0 and frames >= max_frames:
		finish()

func grab():
	var image = get_viewport().get_texture().get_data()
	image.flip_y()
	return image

func differing(a, b):
	a.lock()
	b.lock()
	var count = 0
	for y in range(0, a.get_height(), 2):
		for x in range(0, a.get_width(), 2):
			var d = a.get_pixel(x, y) - b.get_pixel(x, y)
			if abs(d.r) + abs(d.g) + abs(d.b) > 0.1:
				count += 1
	a.unlock()
	b.unlock()
	return float(count) / float(a.get_width() * a.get_height() / 4)

var still_frame
var calm_frame

# Frame 20: the grass before any wind reached it. Frame 80: after 60 frames with the wind off (it must stand
# as before). Frame 200: after 120 frames with the wind on (it must bend).
func run_check():
	if frames == 20:
		still_frame = grab()
	elif frames == 80:
		calm_frame = grab()
		set_wind(true)
	elif frames == 200:
		var windy = grab()
		var calm = differing(still_frame, calm_frame)
		var bent = differing(still_frame, windy)
		if screenshot != "":
			calm_frame.save_png(screenshot.get_basename() + "_off.png")
			windy.save_png(screenshot)
		var ok = calm < 0.001 and bent > 0.01
		print("GUST_DEMO %s: pixels changed with the wind off %.4f, on %.4f" % ["PASS" if ok else "FAIL", calm, bent])
		finish()

func finish():
	var seconds = (OS.get_ticks_msec() - start_ms) / 1000.0
	if screenshot != "" and not check:
		grab().save_png(screenshot)
	var frame_ms = 1000.0 * seconds / frames
	var gust_ms = (step_ms + publish_ms) / frames
	print("GUST_DEMO %d frames in %.2f s: %.1f frames/s (%.1f ms a frame), gust %.1f ms a frame (%.0f %%: step %.1f ms, texture %.1f ms), device %s" % [frames, seconds, frames / seconds, frame_ms, gust_ms, 100.0 * gust_ms / frame_ms, step_ms / frames, publish_ms / frames, wind.get_device_name()])
	get_tree().quit()
