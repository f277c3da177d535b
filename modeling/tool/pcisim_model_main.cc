// pcisim-model: a coronary CT angiogram into a case folder (docs/modeling.md)
int main() { return 0; }
