//! Whether renders with the eye outside the root use tile starts: chosen by the steps a ray
//! took in recent renders with tiles and without.

/// Renders without tile starts after a render with the eye outside the root in which tiles
/// cost more steps a ray than the last render without them (`OutsideTiles`). From outside,
/// a tile's rays only start inside the root: where stops lie at the root's faces (the Menger
/// zoom looks into the root's corner, whose faces are the sponge's) most rays fall back to the
/// skip node and the walks are wasted, while the Mandelbulb's first frames gain from them.
pub const OUTSIDE_TILES_PAUSE: u64 = 16;

/// The choice, while the eye is outside the root, between tile starts and none, by the steps
/// a ray took in recent renders of each kind. A render with tiles is compared with the last
/// one without: costlier, and tiles pause for [`OUTSIDE_TILES_PAUSE`] renders; with no
/// comparison from the last `4 * OUTSIDE_TILES_PAUSE` renders, the next render goes without
/// tiles to measure one, and tiles pause if it was the cheaper. That measuring render can be
/// twice as slow, so the comparison is renewed rarely. It counts renders with the eye outside,
/// not frames: a warm start or a settle renders many times at one frame.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct OutsideTiles {
    /// Renders with the eye outside the root recorded so far (the index of the next). Those
    /// with the eye inside are not counted: the measuring render is the next one outside.
    pub(super) render: u64,
    /// First render that may use tiles.
    pub(super) from: u64,
    /// Steps a ray of the last render with tiles.
    pub(super) tiled: f64,
    /// Steps a ray of the last render without, and its index.
    pub(super) untiled: Option<(f64, u64)>,
    /// The next render goes without tiles to compare.
    pub(super) probing: bool,
}

impl OutsideTiles {
    /// Whether the next render with the eye outside the root may use tiles.
    pub(super) fn allows(&self) -> bool {
        self.render >= self.from
    }

    /// Records a render's steps a ray, `cost`, with tiles or without (`tiled`).
    pub(super) fn record(&mut self, tiled: bool, cost: f64) {
        let r = self.render;
        self.render += 1;
        if tiled {
            self.tiled = cost;
            match self.untiled {
                Some((u, at)) if r < at + 4 * OUTSIDE_TILES_PAUSE => {
                    if cost > u {
                        self.from = r + 1 + OUTSIDE_TILES_PAUSE;
                    }
                }
                _ => {
                    self.from = r + 2;
                    self.probing = true;
                }
            }
        } else {
            self.untiled = Some((cost, r));
            if std::mem::take(&mut self.probing) && cost < self.tiled {
                self.from = r + 1 + OUTSIDE_TILES_PAUSE;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Replays costs per render (`(tiled cost, untiled cost)`, whichever the choice asks
    /// for) and returns which renders used tiles.
    fn replay(renders: u64, cost: impl Fn(u64) -> (f64, f64)) -> Vec<bool> {
        let mut o = OutsideTiles::default();
        (0..renders)
            .map(|f| {
                let tiled = o.allows();
                let (t, u) = cost(f);
                o.record(tiled, if tiled { t } else { u });
                tiled
            })
            .collect()
    }

    #[test]
    fn tiles_stay_on_where_they_save_steps_with_a_measuring_frame_now_and_then() {
        let used = replay(80, |_| (13.0, 20.0));
        let off: Vec<usize> = (0..80).filter(|&f| !used[f]).collect();
        // The first frame measures tiles, the second goes without to compare, and the
        // comparison is renewed once it is 64 frames old.
        assert_eq!(off, [1, 66]);
    }

    #[test]
    fn tiles_pause_where_they_cost_steps_and_are_tried_again_after_each_pause() {
        let used = replay(60, |_| (30.0, 20.0));
        let on: Vec<usize> = (0..60).filter(|&f| used[f]).collect();
        assert_eq!(on, [0, 18, 35, 52]);
    }

    #[test]
    fn tiles_come_back_when_the_frames_without_them_grow_costlier() {
        // Without tiles the steps grow frame by frame (the Mandelbulb's eye approaching).
        let used = replay(60, |f| (20.0, 10.0 + f as f64 * 0.5));
        assert!(!used[5], "tiles cost more at first");
        assert!(used[40..].iter().all(|&u| u), "{used:?}");
    }
}
