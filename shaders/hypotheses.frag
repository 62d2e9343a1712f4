// Sets this hypothesis's bit; the OR logic op merges it with the others'.

flat in uint v_bit;
layout(location = 0) out uint o_bits;

void main() { o_bits = v_bit; }
