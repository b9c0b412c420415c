# 4 WorkerThreadPool tasks sample the wind while the scene steps: each asks sample_wind for 4,096 points over
# and over while GustWind3D steps every physics frame with an ambient wind, a moving box and a fan, and once
# recreates its System (a cell size change) under them. Every answer must be finite, a point far outside
# the domain must get exactly the ambient wind every time, every task must come back with its count, and
# each must have seen many different fields (the sum of its answers), so it sampled during many steps.
extends SceneTree

const TASKS = 4
const POINTS = 1024
const FRAMES = 40
const AMBIENT = Vector3(3, 0, 1)

var wind: GustWind3D
var box: MeshInstance3D
var tasks := []
var results := []
var stop := false
var frames := 0
var start_ms := 0


func worker(index: int) -> void:
	var rng := RandomNumberGenerator.new()
	rng.seed = 7 + index
	var points := PackedVector3Array()
	for i in range(POINTS - 1):
		# Inside the domain, outside it and inside the box alike.
		points.append(Vector3(rng.randf_range(-6, 6), rng.randf_range(-3, 3), rng.randf_range(-6, 6)))
	points.append(Vector3(500, 0, 0))
	var rounds := 0
	var bad := 0
	var not_ambient := 0
	var fields := {}
	while not stop:
		var answers := wind.sample_wind(points)
		if answers.size() != POINTS:
			bad += POINTS
			continue
		var sum := Vector3()
		for v in answers:
			if not (is_finite(v.x) and is_finite(v.y) and is_finite(v.z)):
				bad += 1
			else:
				sum += v
		if answers[POINTS - 1] != AMBIENT:
			not_ambient += 1
		fields[sum] = true
		rounds += 1
		# Leave the 2 cores of CI some time for the steps.
		OS.delay_usec(1000)
	results[index] = {"rounds": rounds, "bad": bad, "fields": fields.size(), "not_ambient": not_ambient}


func _initialize() -> void:
	wind = GustWind3D.new()
	wind.cells = Vector3i(16, 8, 16)
	wind.cell_size = 0.5
	wind.ambient_wind = AMBIENT
	root.add_child(wind)
	var fan := GustEmitter3D.new()
	fan.position = Vector3(-2, 0, 0)
	fan.strength = 6.0
	wind.add_child(fan)
	box = MeshInstance3D.new()
	box.mesh = BoxMesh.new()
	box.add_to_group("gust_obstacles")
	root.add_child(box)
	results.resize(TASKS)
	for i in range(TASKS):
		# High priority: low-priority tasks share a fraction of the pool (threading/worker_pool).
		tasks.append(WorkerThreadPool.add_task(worker.bind(i), true))
	start_ms = Time.get_ticks_msec()


func _process(_delta: float) -> bool:
	frames += 1
	box.position = Vector3(1.5 * cos(frames / 20.0), 0, 1.5 * sin(frames / 20.0))
	if frames == FRAMES / 2:
		wind.cell_size = 0.6
	if frames != FRAMES:
		return false
	stop = true
	for t in tasks:
		WorkerThreadPool.wait_for_task_completion(t)
	var failures := []
	for i in range(TASKS):
		var r = results[i]
		if typeof(r) != TYPE_DICTIONARY:
			failures.append("task %d stopped with an error" % i)
			continue
		print("task %d: %d rounds of %d points, %d different fields, %d non-finite answers" % [i, r.rounds, POINTS, r.fields, r.bad])
		if r.bad > 0:
			failures.append("task %d got %d non-finite answers" % [i, r.bad])
		if r.not_ambient > 0:
			failures.append("task %d got a wind other than the ambient far outside the domain %d times" % [i, r.not_ambient])
		if r.fields < 10:
			failures.append("task %d saw %d different fields only: it sampled during few steps" % [i, r.fields])
	var stats: Dictionary = wind.get_stats()
	print("%d frames in %.1f s, %d steps since the System was recreated" % [frames, (Time.get_ticks_msec() - start_ms) / 1000.0, stats.steps])
	if stats.steps < 10:
		failures.append("the wind took %d steps only" % stats.steps)
	if failures.is_empty():
		print("GUST_TEST PASS")
	else:
		for f in failures:
			print("GUST_TEST FAIL: " + f)
	wind.free()
	box.free()
	quit(0 if failures.is_empty() else 1)
	return true
