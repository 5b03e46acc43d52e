//! What mislab sets in the environment before its first Vulkan call (`gpu::prepare_driver_environment`): lavapipe
//! gets 4-lane code (`LP_NATIVE_VECTOR_WIDTH=128`, half its first compilation on Mesa 25) unless the user chose a
//! width. The variable is read once per process, so each case runs in a child process of this test binary.

use std::process::Command;

/// Run by the parent in a child process (ignored otherwise): prepares the driver's environment and prints the width
/// lavapipe will see.
#[test]
#[ignore = "a child process of lavapipe_gets_4_lanes_unless_the_user_chose"]
fn child_reports_width() {
    assert!(
        std::env::var_os("MISLAB_DRIVER_ENV_CHILD").is_some(),
        "run by lavapipe_gets_4_lanes_unless_the_user_chose"
    );
    mislab::gpu::prepare_driver_environment();
    let width = std::env::var("LP_NATIVE_VECTOR_WIDTH").unwrap_or_default();
    println!("width=[{width}]");
}

fn child_width(user: Option<&str>) -> String {
    let mut cmd = Command::new(std::env::current_exe().expect("the test binary"));
    cmd.args(["--exact", "child_reports_width", "--ignored", "--nocapture", "--test-threads=1"]);
    cmd.env("MISLAB_DRIVER_ENV_CHILD", "1");
    match user {
        Some(w) => cmd.env("LP_NATIVE_VECTOR_WIDTH", w),
        None => cmd.env_remove("LP_NATIVE_VECTOR_WIDTH"),
    };
    let out = cmd.output().expect("the child runs");
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "child failed:\n{text}\n{}", String::from_utf8_lossy(&out.stderr));
    let at = text.find("width=[").unwrap_or_else(|| panic!("the child printed no width:\n{text}")) + 7;
    text[at..].split(']').next().unwrap_or_default().to_string()
}

#[test]
fn lavapipe_gets_4_lanes_unless_the_user_chose() {
    assert_eq!(child_width(None), mislab::gpu::LAVAPIPE_VECTOR_BITS);
    assert_eq!(mislab::gpu::LAVAPIPE_VECTOR_BITS, "128");
    assert_eq!(child_width(Some("256")), "256", "a width the user set is kept");
}
