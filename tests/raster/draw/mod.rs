mod deferred;
mod forward;
