# A skinned figure for the Godot tests: two boxes of 1.6 x 2 x 1.6 m stacked on a Skeleton of two bones, the
# lower box (y 0..2) skinned to bone 0 at the skeleton's origin, the upper one (y 2..4) to bone 1, which rests
# 2 m above it. Skin bind i follows bone i with the inverse of the bone's rest.
extends Reference

const HALF = 0.8

# The 8 corners and 12 triangles of a box from y0 to y1, every vertex on `bone` with weight 1, appended in place
# to Arrays (Pool arrays are values in GDScript, and += makes a new Array).
static func add_box(y0, y1, bone, vertices, bones, weights, indices):
	var base = vertices.size()
	for c in range(8):
		vertices.append(Vector3(HALF if c & 1 else -HALF, y1 if c & 2 else y0, HALF if c & 4 else -HALF))
		for b in [bone, 0, 0, 0]:
			bones.append(b)
		for w in [1.0, 0.0, 0.0, 0.0]:
			weights.append(w)
	for q in [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]]:
		for c in [0, 1, 2, 0, 2, 3]:
			indices.append(base + q[c])

static func mesh():
	var vertices = []
	var bones = []
	var weights = []
	var indices = []
	add_box(0.0, 2.0, 0, vertices, bones, weights, indices)
	add_box(2.0, 4.0, 1, vertices, bones, weights, indices)
	var arrays = []
	arrays.resize(Mesh.ARRAY_MAX)
	arrays[Mesh.ARRAY_VERTEX] = PoolVector3Array(vertices)
	arrays[Mesh.ARRAY_BONES] = PoolIntArray(bones)
	arrays[Mesh.ARRAY_WEIGHTS] = PoolRealArray(weights)
	arrays[Mesh.ARRAY_INDEX] = PoolIntArray(indices)
	var m = ArrayMesh.new()
	m.add_surface_from_arrays(Mesh.PRIMITIVE_TRIANGLES, arrays)
	return m

# A Skeleton with the figure as its MeshInstance child (skeleton path ".."), in `group`. With `with_skin`
# false the MeshInstance has no Skin: Godot's default skin from the rests applies.
static func make(group, with_skin = true):
	var skeleton = Skeleton.new()
	skeleton.add_bone("lower")
	skeleton.add_bone("upper")
	skeleton.set_bone_parent(1, 0)
	skeleton.set_bone_rest(1, Transform(Basis(), Vector3(0, 2, 0)))
	var body = MeshInstance.new()
	body.name = "Body"
	body.mesh = mesh()
	if with_skin:
		var skin = Skin.new()
		skin.add_bind(0, Transform())
		skin.add_bind(1, Transform(Basis(), Vector3(0, -2, 0)))
		body.skin = skin
	body.add_to_group(group)
	skeleton.add_child(body)
	return skeleton
