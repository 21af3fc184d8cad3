mod corpus;
mod export;
mod fuzz;
mod gltf;
mod obj;
mod properties;
