//! The `lash` command.
fn main() {}
