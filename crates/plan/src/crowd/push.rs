//! PIBT's recursive call over continuous steps, shared by [`PibtCrowd`](super::PibtCrowd) and
//! [`lacam_crowd`](super::lacam_crowd).

use super::geometry::closest_approach;
use envfield_grid::Point2;

/// People one candidate step may push at once.
const MAX_PUSHED: usize = 1;

/// One time step's choices as PIBT's recursion makes them.
pub(crate) struct Pushes<'a> {
    /// Everyone's position at the step's start.
    from: &'a [Point2],
    /// This step's end for those who have chosen (fixed ones included).
    pub(crate) next: Vec<Option<Point2>>,
    /// Who has chosen under the calls now open, in order (what a failed call undoes).
    chosen: Vec<usize>,
    /// Calls so far, and the calls after which nobody else is asked to move this step.
    tries: usize,
    budget: usize,
    /// Two body radii.
    disc: f32,
}

impl<'a> Pushes<'a> {
    /// A step from `from` with the ends in `next` already fixed, bodies `disc` apart, at most
    /// `budget` calls of [`Pushes::choose`].
    pub(crate) fn new(
        from: &'a [Point2],
        next: Vec<Option<Point2>>,
        disc: f32,
        budget: usize,
    ) -> Self {
        Self {
            from,
            next,
            chosen: Vec::new(),
            tries: 0,
            budget,
            disc,
        }
    }

    /// PIBT's call for person `i`: takes the first of `ends(i)` (clear of the map, best first)
    /// that is clear in continuous time of every step chosen and whose unchosen person in the way
    /// (at most one) makes way first, by the same call. When none can, or the budget of calls is
    /// spent, returns `false` with every choice made under this call undone: `i` and everyone
    /// they pushed stand where they are, unchosen, and may be asked again.
    pub(crate) fn choose<E: AsRef<[Point2]>>(
        &mut self,
        i: usize,
        ends: &mut impl FnMut(usize) -> E,
    ) -> bool {
        if self.tries >= self.budget {
            return false;
        }
        self.tries += 1;
        let (from, disc) = (self.from[i], self.disc);
        let candidates = ends(i);
        for &to in candidates.as_ref() {
            let clear_of_chosen = (0..self.from.len()).all(|k| {
                k == i
                    || self.next[k]
                        .is_none_or(|end| closest_approach(from, to, self.from[k], end) >= disc)
            });
            if !clear_of_chosen {
                continue;
            }
            let in_the_way: Vec<usize> = (0..self.from.len())
                .filter(|&k| {
                    k != i
                        && self.next[k].is_none()
                        && closest_approach(from, to, self.from[k], self.from[k]) < disc
                })
                .collect();
            if in_the_way.len() > MAX_PUSHED {
                continue;
            }
            let mark = self.chosen.len();
            self.next[i] = Some(to);
            self.chosen.push(i);
            // Someone pushed earlier in this loop may have pushed the next one already, with
            // this step in place: then they are out of the way.
            let made_way = in_the_way
                .iter()
                .all(|&k| self.next[k].is_some() || self.choose(k, ends));
            if made_way {
                return true;
            }
            for k in self.chosen.drain(mark..) {
                self.next[k] = None;
            }
        }
        false
    }
}
