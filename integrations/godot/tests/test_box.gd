# The wind around a box in a Godot scene: 20 steps of 1/60 s with an ambient wind, then the wind at points
# around the box is written to GUST_TEST_OUT ("x y z vx vy vz" a line) for gust_godot_reference to compare.
extends SceneTree

func _initialize():
	var wind = load("res://addons/gust/gust_wind.gdns").new()
	wind.auto_step = false
	wind.cells = Vector3(16, 8, 16)
	wind.cell_size = 0.5
	wind.voxels_per_cell = 2
	wind.ambient = Vector3(3, 0, 0)
	root.add_child(wind)
	var box = MeshInstance.new()
	var cube = CubeMesh.new()
	cube.size = Vector3(2, 2, 2)
	box.mesh = cube
	box.add_to_group("gust_obstacles")
	root.add_child(box)
	for i in range(20):
		if not wind.step(1.0 / 60.0):
			print("GUST_TEST FAIL: step %d failed" % i)
			quit()
			return
	var points = PoolVector3Array()
	for x in range(-7, 8):
		for z in range(-3, 4):
			points.append(Vector3(x * 0.5 + 0.1, 0.3, z * 0.5 + 0.2))
	var velocities = wind.sample(points)
	var file = File.new()
	file.open(OS.get_environment("GUST_TEST_OUT"), File.WRITE)
	for i in range(points.size()):
		var p = points[i]
		var v = velocities[i]
		file.store_line("%.9f %.9f %.9f %.9f %.9f %.9f" % [p.x, p.y, p.z, v.x, v.y, v.z])
	file.close()
	var single = wind.wind_at(points[0])
	if single.distance_to(velocities[0]) > 1e-6:
		print("GUST_TEST FAIL: wind_at %s differs from sample %s" % [single, velocities[0]])
	else:
		print("GUST_TEST PASS %d points, device %s" % [points.size(), wind.get_device_name()])
	for node in [wind, box]:
		root.remove_child(node)
		node.free()
	quit()
