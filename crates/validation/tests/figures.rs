//! The figures of runs: a series without data for the scene is left out (a dry joint draws no
//! film force, a lubricated one does).

use std::path::Path;

use lash_validation::{NoProgress, RunOptions};

fn case(rel: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel)
        .to_string_lossy()
        .into_owned()
}

fn joint_forces_svg(scene: &str, dir: &Path) -> String {
    lash_validation::run(
        &RunOptions {
            case: case(scene),
            out: Some(dir.to_path_buf()),
            t_end: Some(0.2),
            ..Default::default()
        },
        &NoProgress,
    )
    .unwrap();
    std::fs::read_to_string(dir.join("joint_forces.svg")).unwrap()
}

#[test]
fn joint_forces_draw_the_film_only_for_a_lubricated_joint() {
    let d = tempfile::tempdir().unwrap();
    let dry = joint_forces_svg(
        "cases/examples/fourbar_clearance.json",
        &d.path().join("dry"),
    );
    assert!(dry.contains("normal contact force") && !dry.contains("film force"));
    let lub = joint_forces_svg(
        "cases/press/lubricated_150rpm_c0.1.json",
        &d.path().join("lub"),
    );
    assert!(lub.contains("normal contact force") && lub.contains("film force, magnitude"));
}
