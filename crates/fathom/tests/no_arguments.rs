//! `fathom` with no arguments where no window can open: it still renders fathom.png and says
//! why the window did not open. Here the display is set but nothing answers on it (a display
//! number no X server uses), the case a plain "is DISPLAY set" check gets wrong.

use std::process::Command;

#[test]
fn without_a_window_fathom_renders_fathom_png_and_says_why() {
    let dir = std::env::temp_dir().join(format!("fathom-no-args-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_fathom"))
        .current_dir(&dir)
        .env("DISPLAY", ":4711")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stdout}\n{stderr}");
    assert!(stdout.contains("fathom.png"), "{stdout}");
    assert!(stdout.contains("window did not open"), "{stdout}");
    let img = image::open(dir.join("fathom.png")).unwrap();
    assert_eq!((img.width(), img.height()), (1280, 720));
    let _ = std::fs::remove_dir_all(&dir);
}
