//! Writes the press scenes of `lash_model::cases::press_catalogue` as JSON files into the
//! directory given as the only argument (the repository keeps them in `cases/press/`).
//!
//! ```text
//! cargo run -p lash-model --example write_press_cases -- cases/press
//! ```
fn main() {
    let Some(dir) = std::env::args().nth(1) else {
        eprintln!("usage: write_press_cases DIR");
        std::process::exit(2);
    };
    std::fs::create_dir_all(&dir).expect("create the output directory");
    for (stem, scene) in lash_model::cases::press_catalogue() {
        let path = std::path::Path::new(&dir).join(format!("{stem}.json"));
        std::fs::write(&path, scene.to_json_pretty() + "\n").expect("write a case file");
        println!("{}", path.display());
    }
}
