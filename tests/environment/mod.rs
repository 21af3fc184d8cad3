mod brdf_model;
mod corpus;
mod gpu;
mod oracle;
mod properties;
