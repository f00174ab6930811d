//! Writes the scenes of `lash_validation::extremes::catalogue` as JSON files into the
//! directory given as the only argument (the repository keeps them in `cases/extremes/`).
//!
//! ```text
//! cargo run --release -p lash-validation --example write_extreme_cases -- cases/extremes
//! ```
fn main() {
    let Some(dir) = std::env::args().nth(1) else {
        eprintln!("usage: write_extreme_cases DIR");
        std::process::exit(2);
    };
    std::fs::create_dir_all(&dir).expect("create the output directory");
    for s in lash_validation::extremes::catalogue() {
        let path = std::path::Path::new(&dir).join(format!("{}.json", s.stem));
        std::fs::write(&path, s.json()).expect("write a case file");
        println!("{}", path.display());
    }
}
