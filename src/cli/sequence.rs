//! The frames one `strata render` makes: one, or a turntable's views, or a range of the animation's frames; and
//! the file each is written to.
use std::path::{Path, PathBuf};

/// One frame to render.
#[derive(Debug, Clone, PartialEq)]
pub struct FramePlan {
    /// Its number in file names (None: a single frame, written as -o names it).
    pub number: Option<u32>,
    /// The orbit azimuth of a turntable view, in degrees.
    pub theta_degrees: Option<f32>,
    /// The shutter interval of an animation frame, in seconds.
    pub shutter: Option<(f32, f32)>,
}

/// What the command line asked for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Sequence {
    Single,
    /// `--time T`: one frame at time T.
    Time(f32),
    /// `--turntable N` starting at azimuth θ₀.
    Turntable {
        views: u32,
        first_theta: f32,
    },
    /// `--frames A..B`.
    Frames {
        first: u32,
        last: u32,
    },
}

use strata::scene::framing::frame_shutter;

/// Every frame of `sequence`, in order.
pub fn plan(sequence: Sequence, fps: f32, shutter_angle: f32) -> Vec<FramePlan> {
    match sequence {
        Sequence::Single => vec![FramePlan { number: None, theta_degrees: None, shutter: None }],
        Sequence::Time(t) => {
            vec![FramePlan { number: None, theta_degrees: None, shutter: Some(frame_shutter(t, fps, shutter_angle)) }]
        }
        Sequence::Turntable { views, first_theta } => (0..views)
            .map(|k| FramePlan {
                number: Some(k + 1),
                theta_degrees: Some(first_theta + 360.0 * k as f32 / views as f32),
                shutter: None,
            })
            .collect(),
        Sequence::Frames { first, last } => (first..=last)
            .map(|k| FramePlan {
                number: Some(k),
                theta_degrees: None,
                shutter: Some(frame_shutter(k as f32 / fps, fps, shutter_angle)),
            })
            .collect(),
    }
}

/// The file of frame `number`: a run of `#` in the file name becomes the number padded to its length
/// (`thumb.###.png` → `thumb.007.png`); without one, `.NNNN` goes before the extension (`thumb.0007.png`).
pub fn numbered(path: &Path, number: u32) -> PathBuf {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("frame");
    let file = match name.find('#') {
        Some(start) => {
            let run = name[start..].chars().take_while(|c| *c == '#').count();
            format!("{}{number:0run$}{}", &name[..start], &name[start + run..])
        }
        None => match name.rsplit_once('.') {
            Some((stem, ext)) => format!("{stem}.{number:04}.{ext}"),
            None => format!("{name}.{number:04}"),
        },
    };
    path.with_file_name(file)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_go_where_the_hashes_are_or_before_the_extension() {
        assert_eq!(numbered(Path::new("out/thumb.png"), 7), PathBuf::from("out/thumb.0007.png"));
        assert_eq!(numbered(Path::new("thumb.##.png"), 7), PathBuf::from("thumb.07.png"));
        assert_eq!(numbered(Path::new("f_######.exr"), 123), PathBuf::from("f_000123.exr"));
        assert_eq!(numbered(Path::new("x.#.png"), 12), PathBuf::from("x.12.png"), "more digits than hashes");
    }

    #[test]
    fn turntables_step_round_and_frames_open_their_shutters() {
        let t = plan(Sequence::Turntable { views: 4, first_theta: 30.0 }, 24.0, 180.0);
        assert_eq!(t.iter().map(|f| f.theta_degrees.unwrap()).collect::<Vec<_>>(), [30.0, 120.0, 210.0, 300.0]);
        assert_eq!(t[0].number, Some(1));
        let f = plan(Sequence::Frames { first: 10, last: 12 }, 24.0, 180.0);
        assert_eq!(f.len(), 3);
        assert_eq!(f[1].number, Some(11));
        assert_eq!(f[1].shutter, Some((11.0 / 24.0, 11.0 / 24.0 + 0.5 / 24.0)));
        assert_eq!(plan(Sequence::Time(11.0 / 24.0), 24.0, 180.0)[0].shutter, f[1].shutter);
        assert_eq!(plan(Sequence::Time(1.0), 24.0, 0.0)[0].shutter, Some((1.0, 1.0)));
    }
}
