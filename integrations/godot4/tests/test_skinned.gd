# A skinned character is voxelized where its bones put it (headless): the two-box figure of skinned_figure.gd on a
# Skeleton3D whose upper bone is posed 3 m away from its rest, in a 3 m/s wind, 30 steps. Inside the upper box
# where the bone put it and inside the lower box the air is still (the solid's velocity); where the rest pose had
# the upper box the wind blows. Run with a Skin and with Godot's default skin (none set), the skeleton turned and
# moved so its transform counts too. Taking the figure in its bind pose fails it (docs/godot.md).
extends SceneTree

const Figure = preload("res://skinned_figure.gd")
const STEPS = 30

var runs := [true, false]
var wind: GustWind3D
var skeleton: Skeleton3D
var frames := 0
var failures := []


func start(with_skin: bool) -> void:
	wind = GustWind3D.new()
	wind.cells = Vector3i(24, 12, 24)
	wind.cell_size = 0.5
	wind.ambient_wind = Vector3(0, 0, 3)
	wind.position = Vector3(0, 2, 0)
	root.add_child(wind)
	skeleton = Figure.make("gust_obstacles", with_skin)
	# Turned a quarter about y (its +z is the world's +x) and moved 1.5 m along -x.
	skeleton.transform = Transform3D(Basis(Vector3.UP, PI / 2), Vector3(-1.5, 0, 0))
	root.add_child(skeleton)
	# Godot 4's pose replaces the rest: the upper bone 2 m up, as it rests, and 3 m along the skeleton's z.
	skeleton.set_bone_pose_position(1, Vector3(0, 2, 3))
	frames = 0


func _initialize() -> void:
	start(runs[0])


func _process(_delta: float) -> bool:
	frames += 1
	if wind.get_stats().steps < STEPS and frames < 600:
		return false
	var label := "with a Skin" if runs[0] else "with the default skin"
	var rest := skeleton.global_transform * Vector3(0, 3, 0)
	var posed := skeleton.global_transform * Vector3(0, 3, 3)
	var lower := skeleton.global_transform * Vector3(0, 1, 0)
	var v := wind.sample_wind(PackedVector3Array([rest, posed, lower]))
	print("%s, %d steps: rest place %s wind %s, posed place %s wind %s, lower box wind %s" % [label,
		wind.get_stats().steps, rest, v[0], posed, v[1], v[2]])
	if v[0].length() < 1.5:
		failures.append("%s: the air where the rest pose had the upper box moves at %f m/s, under 1.5" % [label, v[0].length()])
	if v[1].length() > 0.3:
		failures.append("%s: the air inside the posed upper box moves at %f m/s, over 0.3" % [label, v[1].length()])
	if v[2].length() > 0.3:
		failures.append("%s: the air inside the lower box moves at %f m/s, over 0.3" % [label, v[2].length()])
	wind.free()
	skeleton.free()
	runs.pop_front()
	if not runs.is_empty():
		start(runs[0])
		return false
	if failures.is_empty():
		print("GUST_TEST PASS")
	else:
		for f in failures:
			print("GUST_TEST FAIL: ", f)
	quit(0 if failures.is_empty() else 1)
	return true
