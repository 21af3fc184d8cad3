mod cli;
mod faults;
mod names;
