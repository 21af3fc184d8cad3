mod cli;
mod errors;
mod recovery;
mod render;
