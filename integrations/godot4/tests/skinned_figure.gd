# A skinned figure for the Godot 4 tests (as integrations/godot/tests/skinned_figure.gd for Godot 3): two boxes
# of 1.6 x 2 x 1.6 m stacked on a Skeleton3D of two bones, the lower box (y 0..2) skinned to bone 0 at the
# skeleton's origin, the upper one (y 2..4) to bone 1, which rests 2 m above it. Skin bind i follows bone i with
# the inverse of the bone's rest.
extends RefCounted

const HALF = 0.8


# The 8 corners and 12 triangles of a box from y0 to y1, every vertex on `bone` with weight 1.
static func add_box(y0: float, y1: float, bone: int, vertices: PackedVector3Array, bones: PackedInt32Array,
		weights: PackedFloat32Array, indices: PackedInt32Array) -> void:
	var base := vertices.size()
	for c in range(8):
		vertices.append(Vector3(HALF if c & 1 else -HALF, y1 if c & 2 else y0, HALF if c & 4 else -HALF))
		bones.append_array([bone, 0, 0, 0])
		weights.append_array([1.0, 0.0, 0.0, 0.0])
	for q in [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]:
		for c in [0, 1, 2, 0, 2, 3]:
			indices.append(base + q[c])


static func mesh() -> ArrayMesh:
	var vertices := PackedVector3Array()
	var bones := PackedInt32Array()
	var weights := PackedFloat32Array()
	var indices := PackedInt32Array()
	add_box(0.0, 2.0, 0, vertices, bones, weights, indices)
	add_box(2.0, 4.0, 1, vertices, bones, weights, indices)
	var arrays := []
	arrays.resize(Mesh.ARRAY_MAX)
	arrays[Mesh.ARRAY_VERTEX] = vertices
	arrays[Mesh.ARRAY_BONES] = bones
	arrays[Mesh.ARRAY_WEIGHTS] = weights
	arrays[Mesh.ARRAY_INDEX] = indices
	var m := ArrayMesh.new()
	m.add_surface_from_arrays(Mesh.PRIMITIVE_TRIANGLES, arrays)
	return m


# A Skeleton3D with the figure as its MeshInstance3D child, in `group`, its skeleton path ".." as importers set it
# (Godot 4's default is empty: an unskinned mesh). With `with_skin`
# false the MeshInstance3D has no Skin: Godot's default skin from the rests applies.
static func make(group: String, with_skin: bool) -> Skeleton3D:
	var skeleton := Skeleton3D.new()
	skeleton.add_bone("lower")
	skeleton.add_bone("upper")
	skeleton.set_bone_parent(1, 0)
	skeleton.set_bone_rest(1, Transform3D(Basis(), Vector3(0, 2, 0)))
	skeleton.reset_bone_poses()
	var body := MeshInstance3D.new()
	body.name = "Body"
	body.mesh = mesh()
	body.skeleton = NodePath("..")
	if with_skin:
		var skin := Skin.new()
		skin.add_bind(0, Transform3D())
		skin.add_bind(1, Transform3D(Basis(), Vector3(0, -2, 0)))
		body.skin = skin
	body.add_to_group(group)
	skeleton.add_child(body)
	return skeleton
