// The output layer is wired into the commands by the lead; until then only its tests use it.
#[allow(dead_code)]
mod output;

fn main() {}
