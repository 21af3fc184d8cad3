mod corpus;
mod gpu;
mod oracle;
mod properties;
