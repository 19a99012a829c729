"""envfield.fmm beyond scikit-fmm's own suite: what it adds (path), what it refuses, and
that NumPy arrays of any layout come in and go out right.

    python3 -m unittest discover -s python/tests -v
"""
import threading
import unittest

import numpy as np

from envfield import fmm


def point_source(shape, at):
    phi = np.ones(shape)
    phi[at] = -1.0
    return phi


class Layouts(unittest.TestCase):
    def test_any_layout_and_dtype_gives_the_same_answer(self):
        rng = np.random.default_rng(1)
        phi = rng.standard_normal((30, 40))
        want = fmm.distance(phi)
        np.testing.assert_array_equal(fmm.distance(np.asfortranarray(phi)), want)
        np.testing.assert_array_equal(fmm.distance(phi.T.copy().T), want)
        big = np.zeros((60, 80))
        big[::2, ::2] = phi
        np.testing.assert_array_equal(fmm.distance(big[::2, ::2]), want)
        np.testing.assert_allclose(fmm.distance(phi.astype(np.float32)),
                                   fmm.distance(phi.astype(np.float32).astype(np.float64)))
        self.assertEqual(fmm.distance(np.sign(phi).astype(int)).dtype, np.float64)

    def test_the_result_is_a_fresh_array_and_phi_is_untouched(self):
        phi = point_source((20, 20), (3, 4))
        before = phi.copy()
        d = fmm.distance(phi)
        self.assertTrue(d.flags.c_contiguous and d.flags.writeable)
        self.assertFalse(np.shares_memory(d, phi))
        np.testing.assert_array_equal(phi, before)

    def test_four_dimensions(self):
        phi = point_source((7, 7, 7, 7), (3, 3, 3, 3))
        d = fmm.distance(phi, order=1)
        self.assertEqual(d.shape, phi.shape)
        # Along an axis the distance grows by one cell per cell.
        np.testing.assert_allclose(np.diff(d[3, 3, 3, 4:]), 1.0)


class Refusals(unittest.TestCase):
    def test_bad_values_are_named(self):
        phi = point_source((5, 5), (2, 2))
        phi[1, 3] = np.nan
        with self.assertRaisesRegex(ValueError, "phi is NaN at flat index 8"):
            fmm.distance(phi)
        with self.assertRaisesRegex(ValueError, "speed is NaN"):
            fmm.travel_time(point_source((4,), 1), [1, np.nan, 1, 1])
        with self.assertRaisesRegex(ValueError, "narrow band is NaN"):
            fmm.distance([-1, 1], narrow=float("nan"))
        with self.assertRaisesRegex(ValueError, "ext_mask must have the same shape|phi and ext_mask"):
            fmm.extension_velocities([-1, 1, 1], [1, 1, 1], ext_mask=[True, False])
        with self.assertRaises(TypeError):
            fmm.distance([-1, 1], order=1.5)
        with self.assertRaisesRegex(ValueError, "phi must be a 1 to 12-D array"):
            fmm.distance(np.float64(1.0))
        with self.assertRaisesRegex(ValueError, "phi must be a 1 to 12-D array"):
            fmm.distance(np.ones((1,) * 13))

    def test_a_path_from_nowhere_is_refused(self):
        mask = np.zeros((10, 10), bool)
        mask[5, :] = True
        d = fmm.distance(np.ma.MaskedArray(point_source((10, 10), (0, 0)), mask))
        with self.assertRaisesRegex(ValueError, "did not reach"):
            fmm.path(d, (8, 8))
        with self.assertRaisesRegex(ValueError, "not a point of the"):
            fmm.path(d, (20, 1))


class Path(unittest.TestCase):
    def test_the_path_goes_round_a_wall_and_gets_shorter_every_step(self):
        n = 60
        mask = np.zeros((n, n), bool)
        mask[30, :45] = True
        t = fmm.travel_time(np.ma.MaskedArray(point_source((n, n), (2, 2)), mask),
                            np.ones((n, n)), dx=0.1)
        p = fmm.path(t, (55.0, 3.0), dx=0.1)
        self.assertEqual(p.shape[1], 2)
        np.testing.assert_allclose(p[0], [55.0, 3.0])
        self.assertLess(np.abs(p[-1] - [2, 2]).max(), 1.5)
        self.assertTrue((p[:, 1] > 44).any(), "it must go round the wall's end")
        cells = np.rint(p).astype(int)
        self.assertFalse(mask[cells[:, 0], cells[:, 1]].any())
        values = [t[tuple(c)] for c in cells]
        self.assertLessEqual(values[-1], values[0])
        # About as long as the field says (the travel time at unit speed is the length).
        length = np.linalg.norm(np.diff(p, axis=0), axis=1).sum() * 0.1
        self.assertLess(abs(length - t[55, 3]), 0.1 * t[55, 3])


class Threads(unittest.TestCase):
    def test_threads_get_the_answers_they_would_alone(self):
        phis = [point_source((200, 200), (i * 40 + 10, 100)) for i in range(4)]
        want = [fmm.distance(p) for p in phis]
        got = [None] * 4

        def run(i):
            got[i] = fmm.distance(phis[i])

        threads = [threading.Thread(target=run, args=(i,)) for i in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        for g, w in zip(got, want):
            np.testing.assert_array_equal(g, w)


if __name__ == "__main__":
    unittest.main()
