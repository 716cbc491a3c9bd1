// The floe pass's uniform block of the tile drawn: one slot per tile in one buffer, its
// range bound for the tile's draw calls (passes.floes.TileSlots).
layout(std140) uniform Tile {
    int first;                   // the tile's first row; frozen, its first status entry (negative)
    int first_floe;              // frozen, the number of its first floe's pose entry
    bool frozen;
    int patch_base;              // the tile's first snow patch
    float thickness;             // m: the tile's level ice
};
