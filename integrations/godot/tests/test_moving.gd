# A moving MeshInstance pushes air: a box carried at 2 m/s through still air sets the air ahead of it in
# motion along its path, where the same box standing still leaves the air still.
extends SceneTree

const SPEED = 2.0

func run(moving):
	var wind = load("res://addons/gust/gust_wind.gdns").new()
	wind.auto_step = false
	wind.cells = Vector3(16, 8, 16)
	wind.cell_size = 0.5
	wind.voxels_per_cell = 2
	root.add_child(wind)
	var box = MeshInstance.new()
	var cube = CubeMesh.new()
	cube.size = Vector3(1, 1, 1)
	box.mesh = cube
	box.translation = Vector3(-1.5, 0, 0)
	box.add_to_group("gust_obstacles")
	root.add_child(box)
	for i in range(12):
		if moving:
			box.translation.x += SPEED / 60.0
		wind.step(1.0 / 60.0)
	var ahead = wind.wind_at(box.translation + Vector3(0.9, 0, 0))
	var result = [ahead, wind.get_moving_obstacles()]
	root.remove_child(wind)
	root.remove_child(box)
	wind.free()
	box.free()
	return result

func _initialize():
	var still = run(false)
	var moved = run(true)
	print("still: ahead %s, moving obstacles %d; moved: ahead %s, moving obstacles %d" % [still[0], still[1], moved[0], moved[1]])
	if moved[1] != 1 or still[1] != 0:
		print("GUST_TEST FAIL: the moved box must be the one moving obstacle")
	elif moved[0].x < 0.25 * SPEED:
		print("GUST_TEST FAIL: the air ahead of the moving box moves at %f m/s, under a quarter of its speed" % moved[0].x)
	elif still[0].length() > 0.01:
		print("GUST_TEST FAIL: the still box set the air moving (%s)" % still[0])
	else:
		print("GUST_TEST PASS")
	quit()
