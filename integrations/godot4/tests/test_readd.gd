# The wind node leaves the tree and comes back, then is freed and a new one added, while the scene runs: its
# System goes with the tree (steps start again from 0 when it returns), the fan below it keeps blowing, and
# no error is logged. Godot runs a frame's physics step before its _process, so by _process of frame f a node
# in the tree since frame a's _process has taken f - a steps (the first node f). At each check the wind 1 m downstream of the fan (pointing along +X) must be faster
# than the ambient wind along X, and far outside the domain exactly the ambient.
extends SceneTree

const AMBIENT = Vector3(1, 0, 0)
const NEAR_FAN = Vector3(-1, 0, 0)
var wind: GustWind3D
var frames := 0
var failures := []


func make_wind() -> GustWind3D:
	var w := GustWind3D.new()
	w.cells = Vector3i(16, 8, 16)
	w.cell_size = 0.5
	w.ambient_wind = AMBIENT
	var fan := GustEmitter3D.new()
	fan.position = Vector3(-2, 0, 0)
	fan.rotation_degrees = Vector3(0, -90, 0) # -Z turned to +X
	fan.strength = 6.0
	w.add_child(fan)
	return w


func check(what: String, steps: int) -> void:
	var stats: Dictionary = wind.get_stats()
	var v := wind.sample_wind(PackedVector3Array([NEAR_FAN, Vector3(500, 0, 0)]))
	print("%s: %d steps, wind near the fan %s, far away %s" % [what, stats.steps, v[0], v[1]])
	if stats.steps != steps:
		failures.append("%s: %d steps, not %d" % [what, stats.steps, steps])
	if not (v[0].x > AMBIENT.x + 0.5):
		failures.append("%s: the wind near the fan %s is no faster than the ambient" % [what, v[0]])
	if v[1] != AMBIENT:
		failures.append("%s: the wind far away is %s, not the ambient" % [what, v[1]])


func _initialize() -> void:
	wind = make_wind()
	root.add_child(wind)


func _process(_delta: float) -> bool:
	frames += 1
	if frames == 20:
		check("first node", 20)
		root.remove_child(wind)
		var out := wind.sample_wind(PackedVector3Array([NEAR_FAN]))
		if out[0] != AMBIENT:
			failures.append("out of the tree the node answers %s, not the ambient" % out[0])
	elif frames == 22:
		root.add_child(wind)
	elif frames == 40:
		check("the node added again", 40 - 22)
		wind.free()
		wind = make_wind()
		root.add_child(wind)
	elif frames == 60:
		check("a new node", 60 - 40)
		if failures.is_empty():
			print("GUST_TEST PASS")
		else:
			for f in failures:
				print("GUST_TEST FAIL: " + f)
		wind.free()
		quit(0 if failures.is_empty() else 1)
		return true
	return false
