mod commands;
mod render_flags;
