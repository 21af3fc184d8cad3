mod deferred;
mod forward;
mod shadows;
