mod cli;
mod errors;
mod formats;
mod recovery;
mod render;
