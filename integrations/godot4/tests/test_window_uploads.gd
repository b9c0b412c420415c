# Forward+ under Xvfb on lavapipe: gust must never race Godot's queue (docs/godot.md, "gust's queue"). While the
# wind node steps with its default settings, 4 WorkerThreadPool tasks upload textures of 512x512 RGBA8 (Godot's
# transfer workers submit them from those threads on Godot's queue, which on lavapipe is its only one). The
# validation layer's thread-safety checks report two threads in one VkQueue, and run_test.sh fails on the
# message. When gust submitted on Godot's queue, it raced those uploads (measured in one run of 60 steps:
# THREADING ERROR, vkQueueSubmit from "godot" and "WorkerThread 0" to "3"). Now gust submits on a device of its
# own, and Godot samples the wind copies it exports: shared, with no texture byte through the CPU. Half-way the
# cell size changes, which recreates the System: Godot's images of the old copies are freed while Godot renders.
extends SceneTree

const BEFORE = 20 # steps before the System is recreated
const STEPS = 40 # steps of the recreated System
var wind: GustWind3D
var tasks := []
var uploads := 0
var mutex := Mutex.new()
var running := true
var frames := 0
var recreated := false


func upload(index: int) -> void:
	var image := Image.create(512, 512, false, Image.FORMAT_RGBA8)
	image.fill(Color(float(index) / 4.0, 0.5, 0.5))
	while running:
		var texture := ImageTexture.create_from_image(image)
		if texture != null:
			mutex.lock()
			uploads += 1
			mutex.unlock()


func _initialize() -> void:
	wind = GustWind3D.new()
	wind.cells = Vector3i(16, 8, 16)
	wind.cell_size = 0.5
	wind.ambient_wind = Vector3(2, 0, 0)
	root.add_child(wind)
	var fan := GustEmitter3D.new()
	fan.strength = 6.0
	wind.add_child(fan)
	for i in range(4):
		tasks.append(WorkerThreadPool.add_task(upload.bind(i), true))


func _process(_delta: float) -> bool:
	frames += 1
	var stats: Dictionary = wind.get_stats()
	if not recreated and stats.steps >= BEFORE:
		recreated = true
		wind.cell_size = 0.6
		return false
	if (not recreated or stats.steps < STEPS) and frames < 600:
		return false
	running = false
	for t in tasks:
		WorkerThreadPool.wait_for_task_completion(t)
	print("%d steps (%s the wind image with Godot, %d texture bytes through the CPU), %d texture uploads from 4 threads"
		% [stats.steps, "sharing" if stats.shares_wind_image else "not sharing", stats.texture_bytes_through_cpu,
		uploads])
	var ok: bool = (recreated and stats.steps >= STEPS and stats.shares_wind_image and stats.texture_bytes_through_cpu == 0
		and uploads >= 8)
	print("GUST_TEST %s" % ["PASS" if ok else "FAIL"])
	wind.free()
	quit(0 if ok else 1)
	return true
