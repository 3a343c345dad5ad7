// caster_masks=off: nothing is listed, nothing is shadowed by a list, and the answer finds the class again.

fn list_pixel(px: vec2<i32>) {}
fn listed_shadowed(px: vec2<i32>) -> bool { return false; }
fn remember_class(px: vec2<i32>, c: u32) {}
fn remembered_class(px: vec2<i32>) -> u32 { return receiver_class(px); }
