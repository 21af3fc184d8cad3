mod draw;
mod mesh;
mod mesh_io;
