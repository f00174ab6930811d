//! End-to-end: an implicit method whose dense n × n matrices do not fit the memory budget is a
//! solver failure (exit 3, "not enough memory") before anything is allocated, never a process
//! killed by the allocator (issue 23: `lash run` on 3000 free bodies under `ulimit -v`
//! printed "memory allocation of 2592000000 bytes failed" and aborted).

mod common;
use common::{json, lash};

use std::process::Command;

/// n free bodies under gravity, no joints: 6n state components.
fn free_bodies(n: usize) -> String {
    let bodies: Vec<String> = (0..n)
        .map(|i| {
            format!(
                "{{\"name\": \"b{i}\", \"mass\": 1.0, \"inertia\": 0.1, \
                 \"position\": [{i}.0, 0.0], \"velocity\": [0.0, 1.0]}}"
            )
        })
        .collect();
    format!(
        "{{\"bodies\": [{}], \"gravity\": [0.0, -9.81], \"t_end\": 0.01}}",
        bodies.join(", ")
    )
}

#[test]
fn max_memory_refuses_the_dense_matrices_with_exit_3() {
    let d = tempfile::tempdir().unwrap();
    let cwd = d.path();
    std::fs::write(cwd.join("free.json"), free_bodies(10)).unwrap();
    // bdf at n = 60: 4 · 60² · 8 = 115 200 bytes.
    let o = lash(
        &["run", "free.json", "--max-memory", "115199", "--out", "r"],
        cwd,
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert!(
        err.contains("not enough memory: bdf's dense Jacobian and LU (4 matrices of 60 × 60 f64)")
            && err.contains("115200 bytes")
            && err.contains("max_memory"),
        "{err}"
    );
    let f = json(&cwd.join("r/failure.json"));
    assert_eq!(f["error"]["kind"], "out_of_memory", "{f}");
    // At the budget the run goes through, and an explicit method needs none of it.
    let ok = lash(
        &["run", "free.json", "--max-memory", "115200", "--out", "a"],
        cwd,
    );
    assert_eq!(
        ok.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    let ok = lash(
        &[
            "run",
            "free.json",
            "--max-memory",
            "1",
            "--method",
            "dopri54",
            "--out",
            "b",
        ],
        cwd,
    );
    assert_eq!(
        ok.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&ok.stderr)
    );
    let o = lash(&["run", "free.json", "--max-memory", "0"], cwd);
    assert_eq!(o.status.code(), Some(2));
}

/// `lash ARGS` in `cwd` under an address-space limit of `kib` KiB, set through the shell as a
/// user would (`ulimit -v`).
fn under_address_limit(cwd: &std::path::Path, kib: u64, args: &str) -> std::process::Output {
    Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v {kib} && exec '{}' {args}",
            env!("CARGO_BIN_EXE_lash")
        ))
        .current_dir(cwd)
        .output()
        .expect("run sh")
}

/// n pendulum links (0.1 m, 1 kg) pinned end to end, the first to the ground: one cluster,
/// whose Jacobian is dense (6n state components).
fn chain(n: usize) -> String {
    let bodies: Vec<String> = (0..n)
        .map(|i| {
            format!(
                "{{\"name\": \"l{i}\", \"mass\": 1.0, \"inertia\": 0.000833, \
                 \"position\": [{}, 0.0], \"points\": {{\"A\": [-0.05, 0.0], \"B\": [0.05, 0.0]}}}}",
                0.1 * i as f64 + 0.05
            )
        })
        .collect();
    let mut joints = vec![
        "{\"type\": \"revolute\", \"name\": \"j0\", \"a\": {\"body\": \"l0\", \"point\": \"A\"}, \
         \"b\": {\"body\": \"ground\", \"at\": [0.0, 0.0]}}"
            .to_string(),
    ];
    joints.extend((1..n).map(|i| {
        format!(
            "{{\"type\": \"revolute\", \"name\": \"j{i}\", \"a\": {{\"body\": \"l{}\", \"point\": \"B\"}}, \
             \"b\": {{\"body\": \"l{i}\", \"point\": \"A\"}}}}",
            i - 1
        )
    }));
    format!(
        "{{\"bodies\": [{}], \"joints\": [{}], \"gravity\": [0.0, -9.81], \"t_end\": 0.001}}",
        bodies.join(", "),
        joints.join(", ")
    )
}

/// A chain of 3 000 links under a 6 GiB address space: one cluster, so Rodas5P (like every
/// implicit method) takes the dense path — 3 matrices of 18 000 × 18 000 f64, 7.8 GB — and
/// is refused before allocating (exit 3), not aborted. (3 000 free bodies, the case this test
/// used before Rodas5P had a sparse path, now run: the next test.)
#[test]
fn a_3000_link_chain_under_a_6_gib_address_space_exits_3_not_abort() {
    let d = tempfile::tempdir().unwrap();
    let cwd = d.path();
    std::fs::write(cwd.join("chain3000.json"), chain(3000)).unwrap();
    let o = under_address_limit(cwd, 6291456, "run chain3000.json --method rodas5p --out r");
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{err}");
    // 3 matrices of 18000 × 18000 f64.
    assert!(
        err.contains("7776000000 bytes") && err.contains("RLIMIT_AS"),
        "{err}"
    );
}

/// 3 000 free bodies at the default method (bdf) and at rodas5p run under a 2 GiB address
/// space (issue 23's target: 3 000 free bodies within 2 GB): the sparse path, whose matrices
/// grow with the block-diagonal pattern's entries (36 per 6 states), not with n².
#[test]
fn three_thousand_bodies_run_within_2_gib_on_the_sparse_path() {
    let d = tempfile::tempdir().unwrap();
    let cwd = d.path();
    std::fs::write(cwd.join("free3000.json"), free_bodies(3000)).unwrap();
    for (method, args) in [
        ("bdf", "run free3000.json --out r"),
        ("rodas5p", "run free3000.json --method rodas5p --out r"),
    ] {
        let o = under_address_limit(cwd, 2097152, args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(0), "{method}: {err}");
        let s = json(&cwd.join("r/summary.json"));
        assert_eq!(s["method"], method);
        assert_eq!(s["t_end"].as_f64(), Some(0.01));
    }
}
