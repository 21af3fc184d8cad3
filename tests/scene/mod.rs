mod batch;
mod cli;
mod corpus;
mod environment_model;
mod errors;
mod examples;
mod properties;
mod renderer;
