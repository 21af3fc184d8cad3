mod deferred;
mod forward;
mod light_between;
mod shadows;
