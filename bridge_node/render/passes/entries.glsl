ivec2 entry_texel(int i, int lines) {
    int k = i >= 0 ? i : -1 - i;
    return ivec2(k % POSE_WIDTH, i >= 0 ? k / POSE_WIDTH : lines - 1 - k / POSE_WIDTH);
}
int entry_of_cell(int first, int cell) { return first >= 0 ? first + cell : first - cell; }
