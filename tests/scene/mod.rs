mod batch;
mod cli;
mod corpus;
mod errors;
mod examples;
mod properties;
mod renderer;
