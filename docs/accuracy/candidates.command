scripts/candidates-vs-time.sh 1000000 2000 23
