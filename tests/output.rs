//! Frame files: PNG and EXR round trips through the same crates, extension handling, and atomic writes that
//! leave the destination untouched when anything fails.
use crate::common;
use common::cli::temp_dir;
use strata::output::{
    linear_to_srgb, srgb_to_linear, to_srgb8, write_atomic, write_frame, write_frame_with_layers, Frame,
};

fn gradient(width: u32, height: u32) -> Frame {
    let pixels = (0..width * height)
        .map(|i| {
            let (x, y) = ((i % width) as f32, (i / width) as f32);
            [x / width as f32, y / height as f32, 0.5 + 0.25 * (x * 0.7).sin(), 1.0 - x / (2.0 * width as f32)]
        })
        .collect();
    Frame::new(width, height, pixels).unwrap()
}

#[test]
fn exr_round_trip_is_bit_exact() {
    let dir = temp_dir("exr");
    let mut frame = gradient(37, 19);
    // Values a PNG could never hold survive an EXR: HDR, negative, tiny.
    frame.pixels[0] = [1234.5, -0.25, 1e-30, 0.0];
    let path = dir.join("frame.exr");
    write_frame(&path, &frame).unwrap();
    let image = exr::prelude::read_first_rgba_layer_from_file(
        &path,
        |size, _| (size.width(), vec![[0f32; 4]; size.width() * size.height()]),
        |(width, pixels), position, (r, g, b, a): (f32, f32, f32, f32)| {
            pixels[position.y() * *width + position.x()] = [r, g, b, a];
        },
    )
    .unwrap();
    let layer = &image.layer_data;
    assert_eq!((layer.size.width(), layer.size.height()), (37, 19));
    let read = &layer.channel_data.pixels.1;
    for (i, (got, want)) in read.iter().zip(&frame.pixels).enumerate() {
        let same = got.iter().zip(want).all(|(g, w)| g.to_bits() == w.to_bits());
        assert!(same, "pixel {i}: wrote {want:?}, read {got:?}");
    }
}

#[test]
fn exr_layers_are_written_by_name() {
    let dir = temp_dir("layers");
    let frame = gradient(8, 4);
    let normals = Frame::new(8, 4, vec![[0.0, 0.0, 1.0, 1.0]; 32]).unwrap();
    let path = dir.join("aov.exr");
    write_frame_with_layers(&path, &frame, &[("normal", &normals)]).unwrap();
    let image = exr::prelude::read_all_flat_layers_from_file(&path).unwrap();
    assert_eq!(image.layer_data.len(), 1);
    let channels = &image.layer_data[0].channel_data.list;
    let names: Vec<String> = channels.iter().map(|c| c.name.to_string()).collect();
    assert_eq!(names, ["A", "B", "G", "R", "normal.A", "normal.B", "normal.G", "normal.R"]);
    let normal_b = channels.iter().find(|c| c.name.to_string() == "normal.B").unwrap();
    match &normal_b.sample_data {
        exr::prelude::FlatSamples::F32(values) => assert!(values.iter().all(|&v| v == 1.0)),
        other => panic!("normal.B is not f32: {other:?}"),
    }
    // PNG cannot hold layers: an error, and no file.
    let png = dir.join("aov.png");
    assert!(write_frame_with_layers(&png, &frame, &[("normal", &normals)]).is_err());
    assert!(!png.exists());
}

#[test]
fn png_round_trip_matches_the_srgb_encoding() {
    let dir = temp_dir("png");
    let frame = gradient(23, 11);
    let path = dir.join("frame.png");
    write_frame(&path, &frame).unwrap();
    let decoded = image::open(&path).unwrap().to_rgba8();
    assert_eq!(decoded.dimensions(), (23, 11));
    assert_eq!(decoded.as_raw(), &to_srgb8(&frame));
    // And the bytes decode back to the linear values within half an 8-bit step of the sRGB curve.
    for (i, px) in decoded.pixels().enumerate() {
        for c in 0..3 {
            let linear = frame.pixels[i][c];
            let back = srgb_to_linear(px[c] as f32 / 255.0);
            let slope_step = (srgb_to_linear((linear_to_srgb(linear) * 255.0 + 0.5) / 255.0) - linear).abs();
            assert!((back - linear).abs() <= slope_step + 1e-6, "pixel {i} channel {c}: {linear} → {back}");
        }
    }
}

#[test]
fn srgb_curve_has_its_standard_values() {
    assert_eq!(linear_to_srgb(0.0), 0.0);
    assert!((linear_to_srgb(1.0) - 1.0).abs() < 1e-6);
    // Mid grey: linear 0.214 is about sRGB 0.5 (IEC 61966-2-1).
    assert!((linear_to_srgb(0.214_041_14) - 0.5).abs() < 1e-4);
    assert!((srgb_to_linear(0.5) - 0.214_041_14).abs() < 1e-6);
    assert_eq!(linear_to_srgb(f32::NAN), 0.0);
    assert_eq!(linear_to_srgb(7.0), linear_to_srgb(1.0));
}

#[test]
fn unknown_or_missing_extensions_are_errors() {
    let dir = temp_dir("ext");
    let frame = gradient(2, 2);
    for name in ["frame.jpg", "frame", "frame.PNG.txt"] {
        let path = dir.join(name);
        let err = write_frame(&path, &frame).unwrap_err().to_string();
        assert!(err.contains(".png or .exr"), "{name}: {err}");
        assert!(!path.exists());
    }
    // Case does not matter.
    write_frame(&dir.join("upper.PNG"), &frame).unwrap();
}

#[test]
fn a_failed_write_leaves_the_destination_untouched() {
    let dir = temp_dir("atomic");
    let path = dir.join("keep.png");
    std::fs::write(&path, b"the previous render").unwrap();
    // An error injected halfway through writing.
    let err = write_atomic(&path, |file| {
        use std::io::Write;
        file.write_all(b"half a picture").unwrap();
        anyhow::bail!("injected failure")
    })
    .unwrap_err();
    assert!(format!("{err:#}").contains("injected failure"));
    assert_eq!(std::fs::read(&path).unwrap(), b"the previous render");
    // No temporary file is left beside it.
    let entries: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(entries, vec![std::ffi::OsString::from("keep.png")]);
}

#[test]
fn a_missing_directory_is_a_clear_error() {
    let dir = temp_dir("nodir");
    let path = dir.join("no/such/dir/frame.png");
    let err = format!("{:#}", write_frame(&path, &gradient(2, 2)).unwrap_err());
    assert!(err.contains("does not exist"), "{err}");
    assert!(!path.exists());
}

#[test]
fn a_frame_must_have_one_pixel_per_position() {
    assert!(Frame::new(3, 3, vec![[0.0; 4]; 8]).is_err());
}
