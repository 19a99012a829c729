"""envfield.rooms: a scene in, a region, a walk and a sit-down out as NumPy arrays, and clear
errors for what cannot be done.

    python3 -m unittest discover -s python/tests -v
"""
import os
import tempfile
import unittest

import numpy as np

from envfield import rooms

# A generated room with a bed in it (generated rooms 0-9 are furnished by seed).
BED_ROOM = 6


class Rooms(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.scene = rooms.Scene.generated(seed=3)
        cls.region = cls.scene.region(seed=3)

    def test_a_walk_and_a_sit_down_come_back_as_arrays(self):
        pts = self.region.points
        self.assertEqual(pts.shape[1], 3)
        self.assertGreater(len(pts), 1000)
        plan = self.region.walk(pts[0], pts[len(pts) // 2])
        self.assertTrue(plan.reached)
        self.assertEqual(plan.kind, "walk")
        self.assertEqual(plan.poses.shape[1:], (22, 3))
        self.assertEqual(len(plan.supported), len(plan.poses))
        # The path starts where asked and ends at the goal; most poses pass both checks.
        np.testing.assert_allclose(plan.path[0], pts[0], atol=1e-5)
        self.assertLess(np.linalg.norm(plan.path[-1] - pts[len(pts) // 2]), 0.05)
        self.assertGreater((plan.supported & plan.collision_free).mean(), 0.9)
        self.assertGreaterEqual(plan.path_ratio, 0.99)
        self.assertGreater(len(self.region.sit_downs), 0)
        sit = self.region.sit_down(0)
        self.assertEqual(sit.kind, "sit")
        self.assertTrue(sit.reached)
        # Seated at the end: the pelvis ends lower than it starts.
        self.assertLess(sit.poses[-1, 0, 2], sit.poses[0, 0, 2] - 0.2)

    def test_a_lie_down_comes_back_as_arrays(self):
        # A generated room with a bed: its region lies down on it.
        scene = rooms.Scene.generated(seed=BED_ROOM)
        region = scene.region(seed=BED_ROOM)
        self.assertGreater(len(region.lie_downs), 0)
        lie = region.lie_down(0)
        self.assertEqual(lie.kind, "lie")
        self.assertTrue(lie.reached)
        self.assertGreater((lie.supported & lie.collision_free).mean(), 0.9)
        # Lying at the end: the head as low as the pelvis, both well below a standing pelvis.
        head = rooms.JOINTS.index("head")
        self.assertLess(abs(lie.poses[-1, head, 2] - lie.poses[-1, 0, 2]), 0.15)
        self.assertLess(lie.poses[-1, 0, 2], lie.poses[0, 0, 2] - 0.2)
        with self.assertRaisesRegex(ValueError, "the region has"):
            region.lie_down(10_000)

    def test_what_cannot_be_done_is_refused_by_name(self):
        with self.assertRaisesRegex(ValueError, "the region has"):
            self.region.sit_down(10_000)
        with self.assertRaisesRegex(ValueError, "learned field"):
            self.region.walk(self.region.points[0], self.region.points[1], planner="ours")
        with self.assertRaisesRegex(ValueError, "planner"):
            self.region.walk(self.region.points[0], self.region.points[1], planner="teleport")
        with self.assertRaisesRegex(ValueError, "start"):
            self.region.walk([50.0, 50.0, 1.0], self.region.points[1])
        with self.assertRaisesRegex(OSError, "no_such_scene.obj"):
            rooms.Scene.read("no_such_scene.obj")

    def test_a_scene_from_a_file(self):
        # A 4 x 3 m floor with a 1 m high box on it, written as OBJ.
        with tempfile.TemporaryDirectory() as d:
            path = os.path.join(d, "floor.obj")
            with open(path, "w") as f:
                f.write("v 0 0 0\nv 4 0 0\nv 4 3 0\nv 0 3 0\nf 1 2 3\nf 1 3 4\n")
            scene = rooms.Scene.read(path)
            lo, hi = scene.bounds
            self.assertAlmostEqual(hi[0] - lo[0], 4.0, places=4)
            self.assertAlmostEqual(hi[1] - lo[1], 3.0, places=4)
            scene_cm = rooms.Scene.read(path, units="cm")
            self.assertAlmostEqual(scene_cm.bounds[1][0] - scene_cm.bounds[0][0], 0.04, places=5)


if __name__ == "__main__":
    unittest.main()
