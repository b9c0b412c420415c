# Forward+ under Xvfb on lavapipe: gust's hazard on Godot's queue (docs/godot.md, "gust's queue"). While the wind
# node steps, 4 WorkerThreadPool tasks upload textures of 512x512 RGBA8 (Godot's transfer workers submit them from
# those threads, on the queue gust would share). The validation layer's thread-safety checks report two threads
# in one VkQueue, and run_test.sh fails on the message. With share_godot_device on, gust's submissions raced those
# uploads (measured in one run of 60 steps: THREADING ERROR, vkQueueSubmit from "godot" and "WorkerThread 0" to
# "3"); with it off, as a game that uploads from threads sets it, gust submits on its own device and nothing races.
extends SceneTree

const STEPS = 60
var wind: GustWind3D
var tasks := []
var uploads := 0
var mutex := Mutex.new()
var running := true
var frames := 0


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
	wind.share_godot_device = false
	root.add_child(wind)
	var fan := GustEmitter3D.new()
	fan.strength = 6.0
	wind.add_child(fan)
	for i in range(4):
		tasks.append(WorkerThreadPool.add_task(upload.bind(i), true))


func _process(_delta: float) -> bool:
	frames += 1
	var stats: Dictionary = wind.get_stats()
	if stats.steps < STEPS and frames < 600:
		return false
	running = false
	for t in tasks:
		WorkerThreadPool.wait_for_task_completion(t)
	print("%d steps (%s Godot's device), %d texture uploads from 4 threads" % [stats.steps,
		"sharing" if stats.shares_godot_device else "not sharing", uploads])
	var ok: bool = stats.steps >= STEPS and not stats.shares_godot_device and uploads >= 8
	print("GUST_TEST %s" % ["PASS" if ok else "FAIL"])
	wind.free()
	quit(0 if ok else 1)
	return true
