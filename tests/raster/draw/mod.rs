mod deferred;
mod denoise;
mod forward;
mod light_between;
mod shadows;
mod surfaces;
