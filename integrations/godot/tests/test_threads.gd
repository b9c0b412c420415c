# Several threads sample the wind at once while the physics steps: 4 GDScript Threads, each through its own
# GustSampler (Godot 3.2 crashes when two threads call one NativeScript instance at once, docs/godot.md), ask
# sample() for 4,096 points over and over while GustWind steps in _physics_process (auto_step) with a wind, a
# moving box and a fan, and once recreates its System (a cell size change) under them. Every answer must be
# finite, every thread must come back with its count (a script error in a thread returns none), and each must
# have seen many different fields (the sum of its answers), so it sampled during many steps.
extends SceneTree

const THREADS = 4
const POINTS = 4096
const FRAMES = 90

var wind
var box
var threads = []
var samplers = []
var stop = false
var frames = 0
var start_ms = 0

func worker(index):
	var sampler = samplers[index]
	var rng = RandomNumberGenerator.new()
	rng.seed = 7 + index
	var points = PoolVector3Array()
	for i in range(POINTS):
		# Inside the domain, outside it and inside the box alike.
		points.append(Vector3(rng.randf_range(-6, 6), rng.randf_range(-3, 3), rng.randf_range(-6, 6)))
	var rounds = 0
	var bad = 0
	var winds_seen = {}
	while not stop:
		var answers = sampler.sample(points)
		if answers.size() != POINTS:
			bad += POINTS
		var sum = Vector3()
		for v in answers:
			if is_nan(v.x) or is_nan(v.y) or is_nan(v.z) or is_inf(v.x) or is_inf(v.y) or is_inf(v.z):
				bad += 1
			else:
				sum += v
		winds_seen[sum] = true
		rounds += 1
	return {"rounds": rounds, "bad": bad, "fields": winds_seen.size()}

func _initialize():
	wind = load("res://addons/gust/gust_wind.gdns").new()
	wind.cells = Vector3(16, 8, 16)
	wind.cell_size = 0.5
	wind.voxels_per_cell = 2
	wind.ambient = Vector3(3, 0, 1)
	root.add_child(wind)
	var fan = load("res://addons/gust/gust_emitter.gdns").new()
	fan.translation = Vector3(-2, 0, 0)
	fan.strength = 6.0
	wind.add_child(fan)
	box = MeshInstance.new()
	box.mesh = CubeMesh.new()
	box.add_to_group("gust_obstacles")
	root.add_child(box)
	for i in range(THREADS):
		var sampler = load("res://addons/gust/gust_sampler.gdns").new()
		sampler.set_wind(wind)
		samplers.append(sampler)
	for i in range(THREADS):
		var thread = Thread.new()
		thread.start(self, "worker", i)
		threads.append(thread)
	start_ms = OS.get_ticks_msec()

func _iteration(_delta):
	frames += 1
	box.translation = Vector3(1.5 * cos(frames / 20.0), 0, 1.5 * sin(frames / 20.0))
	if frames == FRAMES / 2:
		wind.cell_size = 0.6
	if frames != FRAMES:
		return false
	stop = true
	var failures = []
	for i in range(THREADS):
		var r = threads[i].wait_to_finish()
		if typeof(r) != TYPE_DICTIONARY:
			failures.append("thread %d stopped with an error" % i)
			continue
		print("thread %d: %d rounds of %d points, %d different fields, %d non-finite answers" % [i, r["rounds"], POINTS, r["fields"], r["bad"]])
		if r["bad"] > 0:
			failures.append("thread %d got %d non-finite answers" % [i, r["bad"]])
		if r["fields"] < 10:
			failures.append("thread %d saw %d different fields only: it sampled during few steps" % [i, r["fields"]])
	print("%d frames in %.1f s, %d steps since the System was recreated" % [frames, (OS.get_ticks_msec() - start_ms) / 1000.0, wind.get_steps()])
	if wind.get_steps() < 10:
		failures.append("the wind took %d steps only" % wind.get_steps())
	if failures.empty():
		print("GUST_TEST PASS")
	else:
		for f in failures:
			print("GUST_TEST FAIL: " + f)
	quit()
	return false

func _finalize():
	root.remove_child(wind)
	root.remove_child(box)
	wind.free()
	box.free()
