//! Stereo layouts on the CPU: the views of a [`Projection`] rendered one after the other are
//! laid out in one frame, side by side (left eye on the left) or top/bottom (left eye on top,
//! the omni-directional stereo layout 360-degree players read).

use fathom_core::Projection;
use fathom_core::frame::Frame;

/// Lays out equally sized per-eye `views` (one for mono, left then right for stereo) in the
/// output frame of `projection`. A mono view is returned as it is, without a copy.
pub fn assemble(projection: Projection, mut views: Vec<Frame>) -> Frame {
    assert_eq!(views.len(), projection.eyes() as usize, "one view per eye");
    if views.len() == 1 {
        return views.pop().expect("one view");
    }
    let (w, h) = (views[0].width, views[0].height);
    let (ow, oh) = projection.output_size(w, h);
    let mut f = Frame::new(ow, oh);
    for (eye, v) in views.iter().enumerate() {
        assert_eq!(
            (v.width, v.height),
            (w, h),
            "views of one frame differ in size"
        );
        for y in 0..h {
            for x in 0..w {
                let (ox, oy) = projection.output_pixel(eye as u32, x, y, w, h);
                let (i, o) = (v.index(x, y), f.index(ox, oy));
                f.copy_pixel(o, v, i);
            }
        }
    }
    f
}

/// The per-eye views of an output frame of `projection`: the inverse of [`assemble`], so
/// screen-space post effects can run on each eye's view of a frame rendered whole (the GPU's).
pub fn split(projection: Projection, frame: Frame) -> Vec<Frame> {
    let eyes = projection.eyes();
    if eyes == 1 {
        return vec![frame];
    }
    let (w, h) = match projection {
        Projection::SideBySide { .. } => (frame.width / 2, frame.height),
        _ => (frame.width, frame.height / 2),
    };
    (0..eyes)
        .map(|eye| {
            let mut v = Frame::new(w, h);
            for y in 0..h {
                for x in 0..w {
                    let (ox, oy) = projection.output_pixel(eye, x, y, w, h);
                    let (i, o) = (v.index(x, y), frame.index(ox, oy));
                    v.copy_pixel(i, &frame, o);
                }
            }
            v
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn views_are_laid_out_left_right_and_top_bottom() {
        let mut l = Frame::new(2, 1);
        let mut r = Frame::new(2, 1);
        l.steps = vec![1, 2];
        r.steps = vec![3, 4];
        let sbs = Projection::SideBySide {
            eye_separation: 0.1,
        };
        let f = assemble(sbs, vec![l.clone(), r.clone()]);
        assert_eq!(
            (f.width, f.height, f.steps.clone()),
            (4, 1, vec![1, 2, 3, 4])
        );
        let ods = Projection::Ods {
            eye_separation: 0.1,
        };
        let f = assemble(ods, vec![l.clone(), r.clone()]);
        assert_eq!(
            (f.width, f.height, f.steps.clone()),
            (2, 2, vec![1, 2, 3, 4])
        );
        // split undoes assemble.
        assert_eq!(split(ods, f), vec![l.clone(), r.clone()]);
        assert_eq!(
            split(sbs, assemble(sbs, vec![l.clone(), r.clone()])),
            vec![l, r]
        );
    }
}
