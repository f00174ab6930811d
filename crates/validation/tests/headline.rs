//! The default run (`cargo run --release`): its table, its files, and the claims it makes.

use lash_solver::Method;
use lash_validation::NoProgress;

#[test]
fn default_run_compares_rk4_with_the_best_adaptive_method() {
    let d = tempfile::tempdir().unwrap();
    let h = lash_validation::default_run(Some(d.path().to_path_buf()), &NoProgress)
        .unwrap()
        .result;
    assert_eq!(h.cases.len(), 3);
    for c in &h.cases {
        let rk4 = &c.rk4;
        assert_eq!(rk4.method, Method::Rk4);
        // RK4 runs without event location (docs/model.md §7).
        assert_eq!(rk4.events, 0);
        // The adaptive method reached RK4's accuracy.
        assert!(
            c.matched,
            "{}: {:?} vs {:?}",
            c.case, c.adaptive.error, rk4.error
        );
        assert!(c.adaptive.error.unwrap() <= rk4.error.unwrap());
        // The reference is converged far below the errors it measures.
        let agree = c.reference_agreement.as_ref().unwrap().headline();
        assert!(agree < 1e-2 * rk4.error.unwrap(), "{}: {agree}", c.case);
        assert!(d.path().join(&c.case).join("summary.json").is_file());
        assert!(d.path().join(&c.case).join("trajectory.csv").is_file());
    }
    let by = |label: &str| h.cases.iter().find(|c| c.label == label).unwrap();
    // The lubricated case: the film makes RK4 need 2e-6 s steps; BDF does the same accuracy
    // with at least 100× fewer RHS evaluations.
    let lub = by("lubricated");
    assert_eq!(lub.adaptive.method, Method::Bdf);
    assert!(lub.rk4.rhs_evals > 100 * lub.adaptive.rhs_evals);
    let m = lub.metrics.as_ref().unwrap();
    assert!(m.eps_max.unwrap() < 1.0 && m.contact_onsets == Some(0));
    // The dry case is measured over the first half revolution (chaotic, docs/model.md §9).
    assert_eq!(by("dry").window.label, "first half revolution");
    assert_eq!(by("ideal").window.label, "last revolution");
    for f in [
        "README.md",
        "default.json",
        "slider_acceleration.png",
        "slider_acceleration.svg",
        "orbits.png",
        "orbits.svg",
    ] {
        assert!(d.path().join(f).is_file(), "{f}");
    }
    let md = std::fs::read_to_string(d.path().join("README.md")).unwrap();
    assert!(md.contains("| lubricated | bdf | rtol "));
    assert!(md.contains("checked by esdirk34"));
    readme_shows_the_table_the_run_prints(&md);
}

/// README.md ("What the default run shows") holds the comparison table the run prints: every
/// cell but the wall times (column 5), which vary from run to run. `LASH_BLESS=1` rewrites
/// the README's table with this run's.
fn readme_shows_the_table_the_run_prints(printed: &str) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../README.md");
    let readme = std::fs::read_to_string(&path).unwrap();
    let marker = "<!-- The table `cargo run --release` prints;";
    let at = readme.find(marker).expect("the README's table marker");
    let start = at + readme[at..].find('\n').unwrap() + 1;
    let end = start + readme[start..].find("\n\n").unwrap();
    let shown: Vec<&str> = readme[start..end].lines().collect();
    let run = comparison_table(printed);
    if std::env::var_os("LASH_BLESS").is_some() {
        let text = format!("{}{}{}", &readme[..start], run.join("\n"), &readme[end..]);
        std::fs::write(&path, text).unwrap();
        return;
    }
    assert_eq!(
        shown.len(),
        run.len(),
        "README:\n{}\nrun:\n{}",
        shown.join("\n"),
        run.join("\n")
    );
    assert_eq!(run.len(), 2 + 6);
    for (a, b) in shown.iter().zip(&run) {
        let cells = |l: &str| -> Vec<String> {
            l.split('|')
                .enumerate()
                .filter(|(k, _)| *k != 5)
                .map(|(_, c)| c.trim().to_string())
                .collect()
        };
        assert_eq!(cells(a), cells(b), "README: {a}\nrun:    {b}");
    }
}

/// The comparison table of the default run's markdown (its first table: header, rule and one
/// row per run), the one README.md shows.
fn comparison_table(markdown: &str) -> Vec<String> {
    markdown
        .lines()
        .skip_while(|l| !l.starts_with("| case | method |"))
        .take_while(|l| l.starts_with('|'))
        .map(str::to_string)
        .collect()
}
