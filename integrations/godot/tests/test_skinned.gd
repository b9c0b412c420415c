# A skinned character is voxelized where its bones put it: a two-box figure on a Skeleton (skinned_figure.gd)
# whose upper bone is posed 3 m away from its rest, in a 3 m/s wind. Inside the upper box where the bone put it
# the air is still (the solid's velocity); where the rest pose would have had it the wind blows. Run with a Skin
# and with Godot's default skin (none set), the skeleton turned and moved so its transform counts too.
extends SceneTree

const Figure = preload("res://skinned_figure.gd")

func run(with_skin):
	var wind = load("res://addons/gust/gust_wind.gdns").new()
	wind.auto_step = false
	wind.cells = Vector3(24, 12, 24)
	wind.cell_size = 0.5
	wind.voxels_per_cell = 2
	wind.ambient = Vector3(0, 0, 3)
	wind.translation = Vector3(0, 2, 0)
	root.add_child(wind)
	var skeleton = Figure.make("gust_obstacles", with_skin)
	# Turned a quarter about y (its +z is the world's +x) and moved 1.5 m along -x.
	skeleton.transform = Transform(Basis(Vector3.UP, PI / 2), Vector3(-1.5, 0, 0))
	root.add_child(skeleton)
	skeleton.set_bone_pose(1, Transform(Basis(), Vector3(0, 0, 3)))
	for i in range(30):
		wind.step(1.0 / 60.0)
	var rest = skeleton.global_transform.xform(Vector3(0, 3, 0))
	var posed = skeleton.global_transform.xform(Vector3(0, 3, 3))
	var lower = skeleton.global_transform.xform(Vector3(0, 1, 0))
	var result = [rest, wind.wind_at(rest), posed, wind.wind_at(posed), wind.wind_at(lower)]
	root.remove_child(wind)
	root.remove_child(skeleton)
	wind.free()
	skeleton.free()
	return result

func _initialize():
	var failures = []
	for with_skin in [true, false]:
		var r = run(with_skin)
		var label = "with a Skin" if with_skin else "with the default skin"
		print("%s: rest place %s wind %s, posed place %s wind %s, lower box wind %s" % [label, r[0], r[1], r[2], r[3], r[4]])
		if r[1].length() < 1.5:
			failures.append("%s: the air where the rest pose had the upper box moves at %f m/s, under 1.5" % [label, r[1].length()])
		if r[3].length() > 0.3:
			failures.append("%s: the air inside the posed upper box moves at %f m/s, over 0.3" % [label, r[3].length()])
		if r[4].length() > 0.3:
			failures.append("%s: the air inside the lower box moves at %f m/s, over 0.3" % [label, r[4].length()])
	if failures.empty():
		print("GUST_TEST PASS")
	else:
		for f in failures:
			print("GUST_TEST FAIL: " + f)
	quit()
