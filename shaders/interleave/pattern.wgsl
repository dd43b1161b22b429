// Image size, interleave pattern n×m and sub-buffer size ceil(width/n) × ceil(height/m)
// (Segovia 2006 §3.2), set per pipeline as override constants.
override width: u32 = 1u;
override height: u32 = 1u;
override n: u32 = 1u;
override m: u32 = 1u;
override sub_width: u32 = 1u;
override sub_height: u32 = 1u;
