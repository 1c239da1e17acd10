document.write('</script>');
