//! Robot colours: one palette shared by the plots and the replay page, so a
//! robot has the same colour in both. It cycles after 16 robots. Red is
//! left out (collisions are red), and so are greys (obstacles, walls).

/// The palette, as RGB.
pub const PALETTE: [[u8; 3]; 16] = [
    [0x1f, 0x77, 0xb4],
    [0xff, 0x7f, 0x0e],
    [0x2c, 0xa0, 0x2c],
    [0x94, 0x67, 0xbd],
    [0x8c, 0x56, 0x4b],
    [0xe3, 0x77, 0xc2],
    [0xbc, 0xbd, 0x22],
    [0x17, 0xbe, 0xcf],
    [0x39, 0x3b, 0x79],
    [0x63, 0x79, 0x39],
    [0x8c, 0x6d, 0x31],
    [0x7b, 0x41, 0x73],
    [0x31, 0x82, 0xbd],
    [0xe6, 0x55, 0x0d],
    [0x31, 0xa3, 0x54],
    [0x75, 0x6b, 0xb1],
];

/// Colour of people, RGB: one sandy brown for all, apart from the robots'
/// palette and the obstacles' grey.
pub const PERSON: [u8; 3] = [0xf4, 0xa4, 0x60];

/// Colour of collision marks, RGB.
pub const COLLISION: [u8; 3] = [0xe3, 0x1a, 0x1c];

/// Colour of the robot with colour index `index` (see
/// [`RunData::robot_index`](crate::RunData::robot_index)).
pub fn robot_color(index: usize) -> [u8; 3] {
    PALETTE[index % PALETTE.len()]
}

/// `#rrggbb` of an RGB colour.
pub fn hex(c: [u8; 3]) -> String {
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}
