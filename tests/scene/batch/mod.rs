mod cli;
mod faults;
mod names;
mod scale;
