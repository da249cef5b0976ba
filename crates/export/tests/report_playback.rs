//! The report's 3D view states what it plays, with the numbers the player's data uses.
use export::report::playback_note;
use export::viewer::{view_data_js, ViewSequence};
use mesh_core::sequence::MeshSequence;

fn view(n_frames: usize) -> ViewSequence {
    let faces = vec![[0, 1, 2]];
    let frames = (0..n_frames)
        .map(|k| {
            let x = k as f64 * 0.01;
            vec![[x, 0.0, 0.0].into(), [x + 1.0, 0.0, 0.0].into(), [x, 1.0, 0.0].into()]
        })
        .collect();
    ViewSequence { label: format!("s{n_frames}"), seq: MeshSequence::new(faces, frames) }
}

/// The `SURFCAP_VIEW` document of the view data script.
fn doc(js: &str) -> serde_json::Value {
    let start = js.find('{').unwrap();
    let end = js.rfind('}').unwrap();
    serde_json::from_str(&js[start..=end]).unwrap()
}

#[test]
fn the_note_states_the_players_stride_frames_and_rate() {
    for (lengths, max_frames, fps) in [(vec![54, 40], 20, 25.0), (vec![12], 60, 50.0), (vec![100, 100, 99], 52, 20.0)] {
        let views: Vec<ViewSequence> = lengths.iter().map(|&n| view(n)).collect();
        let d = doc(&view_data_js(&views, fps, max_frames));
        let (stride, shown) = (d["stride"].as_u64().unwrap(), d["nFrames"].as_u64().unwrap());
        assert_eq!(d["fps"].as_f64().unwrap(), fps);
        let longest = *lengths.iter().max().unwrap();
        let note = playback_note(&views, max_frames, fps);
        let which = if stride == 1 { "Every frame".to_string() } else { format!("One frame in {stride}") };
        assert_eq!(
            note,
            format!("{which} of {longest} is shown ({shown} frames), each for {stride}/{fps} s: the capture's speed."),
        );
        // Real speed: the shown frames span the sequence's duration.
        assert!((shown * stride) as f64 / fps >= longest as f64 / fps);
        assert!(((shown - 1) * stride) as f64 / fps < longest as f64 / fps);
    }
}
