# Bad values give errors in Godot's log (run_godot_test.sh checks their text) and leave the node working:
# a negative cell size and too few cells are refused, a Spatial in the obstacle group is skipped, and skins gust
# cannot pose (no Skeleton at the skeleton path, a bind to a bone the skeleton lacks) are taken in their rest pose.
extends SceneTree

const Figure = preload("res://skinned_figure.gd")

func _initialize():
	var wind = load("res://addons/gust/gust_wind.gdns").new()
	wind.auto_step = false
	wind.cells = Vector3(16, 8, 16)
	wind.cell_size = 0.5
	wind.cell_size = -1.0
	wind.cells = Vector3(4, 8, 16)
	wind.quality = 7
	wind.ambient = Vector3(1, 0, 0)
	root.add_child(wind)
	var stray = Spatial.new()
	stray.add_to_group("gust_obstacles")
	root.add_child(stray)
	var box = MeshInstance.new()
	box.mesh = CubeMesh.new()
	box.add_to_group("gust_obstacles")
	root.add_child(box)
	var lone = MeshInstance.new()
	lone.mesh = Figure.mesh()
	lone.skin = Skin.new()
	lone.skeleton = NodePath("nowhere")
	lone.add_to_group("gust_obstacles")
	root.add_child(lone)
	var bad = Figure.make("gust_obstacles")
	bad.get_node("Body").skin.set_bind_bone(1, 5)
	root.add_child(bad)
	var emitter = load("res://addons/gust/gust_emitter.gdns").new()
	emitter.radius = -2.0
	wind.add_child(emitter)
	var ok = true
	for i in range(3):
		ok = ok and wind.step(1.0 / 60.0)
	if wind.cell_size != 0.5 or wind.cells != Vector3(16, 8, 16) or wind.quality != 1 or emitter.radius != 1.0:
		print("GUST_TEST FAIL: a bad value was taken (cell_size %f, cells %s, quality %d, radius %f)" % [wind.cell_size, wind.cells, wind.quality, emitter.radius])
	elif not ok or wind.get_steps() != 3:
		print("GUST_TEST FAIL: the node stopped working after the bad values")
	else:
		print("GUST_TEST PASS")
	for node in [wind, box, lone, bad]:
		root.remove_child(node)
		node.free()
	quit()
