# Imports a GLB into Blender headless and prints what came in: objects, meshes, the joint
# nodes (empties), animations (actions), and how far the first person's pelvis moves.
# Usage: blender -b --factory-startup --python scripts/blender_import_check.py -- FILE.glb
# (checked by hand with Debian's Blender 3.4.1; not part of CI).
import bpy, sys
import numpy
if not hasattr(numpy, "bool"):
    numpy.bool = bool  # Debian bookworm: Blender 3.4 asks numpy 1.24 for an alias it removed
bpy.ops.wm.read_factory_settings(use_empty=True)
path = sys.argv[sys.argv.index('--') + 1]
bpy.ops.import_scene.gltf(filepath=path)
objs = bpy.data.objects
print("IMPORT objects", len(objs), "meshes", sum(o.type == 'MESH' for o in objs), "empties", sum(o.type == 'EMPTY' for o in objs), "actions", len(bpy.data.actions))
# Blender keeps one glTF animation active and stashes the others in NLA tracks: report the
# pelvis that moves along the active one.
sc = bpy.context.scene
for o in objs:
    a = o.animation_data.action if o.animation_data else None
    if o.name.endswith(':pelvis') and a and a.frame_range[1] > a.frame_range[0]:
        sc.frame_set(int(a.frame_range[0])); p0 = o.matrix_world.translation.copy()
        sc.frame_set(int(a.frame_range[1])); p1 = o.matrix_world.translation.copy()
        print("IMPORT pelvis", o.name, "frames", tuple(a.frame_range), "moved", round((p1 - p0).length, 3), "m")
        break
